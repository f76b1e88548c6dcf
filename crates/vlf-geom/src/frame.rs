//! The per-direction rotation (`formats/vlf.md` §5.4): rows `t1, t2, ω`, so `M ω = +z`.

/// The frame of Duff et al. 2017, "Building an Orthonormal Basis, Revisited" (JCGT 6(1)).
/// Branch-free and trig-free: only `+ − × /`, so every machine computes the same bits.
pub fn frame(w: [f64; 3]) -> [f64; 9] {
    let [x, y, z] = w;
    let s = 1f64.copysign(z);
    let a = -1.0 / (s + z);
    let b = x * y * a;
    [1.0 + s * x * x * a, s * b, -s * x, b, s + y * y * a, -y, x, y, z]
}

/// `M v` for a row-major 3×3 matrix.
#[inline(always)]
pub fn mul(m: &[f64; 9], v: [f64; 3]) -> [f64; 3] {
    [
        m[0] * v[0] + m[1] * v[1] + m[2] * v[2],
        m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
        m[6] * v[0] + m[7] * v[1] + m[8] * v[2],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lattice::Lattice;

    #[test]
    fn frames_are_orthonormal_rotations_taking_omega_to_z() {
        let lat = Lattice::new(12);
        for w in lat.directions() {
            let m = frame(w);
            let z = mul(&m, w);
            assert!((z[0]).abs() < 1e-15 && (z[1]).abs() < 1e-15 && (z[2] - 1.0).abs() < 1e-15);
            let rows = [[m[0], m[1], m[2]], [m[3], m[4], m[5]], [m[6], m[7], m[8]]];
            for i in 0..3 {
                for j in 0..3 {
                    let d: f64 = (0..3).map(|k| rows[i][k] * rows[j][k]).sum();
                    assert!((d - if i == j { 1.0 } else { 0.0 }).abs() < 1e-14);
                }
            }
            let det = rows[0][0] * (rows[1][1] * rows[2][2] - rows[1][2] * rows[2][1])
                - rows[0][1] * (rows[1][0] * rows[2][2] - rows[1][2] * rows[2][0])
                + rows[0][2] * (rows[1][0] * rows[2][1] - rows[1][1] * rows[2][0]);
            assert!((det - 1.0).abs() < 1e-14, "a rotation, not a reflection");
        }
    }
}
