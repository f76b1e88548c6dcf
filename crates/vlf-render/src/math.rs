//! Three-vectors of f64: positions, directions and linear RGB colours alike.

pub type V3 = [f64; 3];

#[inline(always)]
pub fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
#[inline(always)]
pub fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
#[inline(always)]
pub fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
/// Componentwise product (colour times colour).
#[inline(always)]
pub fn mul(a: V3, b: V3) -> V3 {
    [a[0] * b[0], a[1] * b[1], a[2] * b[2]]
}
#[inline(always)]
pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
#[inline(always)]
pub fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
#[inline(always)]
pub fn length(a: V3) -> f64 {
    dot(a, a).sqrt()
}
/// `a` scaled to unit length, or `None` if it has no direction (zero, or not finite).
#[inline]
pub fn normalize(a: V3) -> Option<V3> {
    let len = length(a);
    (len > 0.0 && len.is_finite()).then(|| scale(a, 1.0 / len))
}
/// `a + b·s`.
#[inline(always)]
pub fn madd(a: V3, b: V3, s: f64) -> V3 {
    [a[0] + b[0] * s, a[1] + b[1] * s, a[2] + b[2] * s]
}
/// The largest component.
#[inline(always)]
pub fn max_component(a: V3) -> f64 {
    a[0].max(a[1]).max(a[2])
}
/// Mirror reflection of direction `d` about the unit normal `n`.
#[inline(always)]
pub fn reflect(d: V3, n: V3) -> V3 {
    madd(d, n, -2.0 * dot(d, n))
}
pub fn widen(v: [f32; 3]) -> V3 {
    v.map(f64::from)
}
