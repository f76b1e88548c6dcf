//! Classical ray tracing (Whitted 1980, the paper's §1 framing): a primary ray per sample; at each
//! hit, Lambert and Phong shading under every light that a shadow ray (an any-hit query) finds
//! unobstructed, plus an ambient term; then a mirror-reflected ray and a refracted ray (Snell's
//! law, split by Schlick's Fresnel approximation, total internal reflection folded into the
//! reflection) until `max_depth` or until a ray's weight no longer matters.
//!
//! Every pixel is computed on its own from its samples' rays, so a frame does not depend on the
//! thread count, and two tracers that return the same hits (the field and the kd-tree share the
//! triangle kernel) give the same frame, bit for bit.

use crate::light::Light;
use crate::math::{V3, add, dot, madd, max_component, mul, normalize, reflect, scale, widen};
use crate::scene::Scene;
use crate::view::View;
use rayon::prelude::*;
use vlf_geom::{Intersector, Ray, TraceStats};

/// What is seen where rays leave the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Background {
    /// A soft sky: pale at the horizon (y = 0), blue overhead, darker below.
    Sky,
    /// One linear RGB colour.
    Solid(V3),
}

impl Background {
    fn colour(&self, dir: V3) -> V3 {
        match *self {
            Background::Solid(c) => c,
            Background::Sky => {
                let y = dir[1].clamp(-1.0, 1.0);
                let (from, to, t) = if y >= 0.0 {
                    ([0.80, 0.83, 0.88], [0.30, 0.44, 0.70], y.sqrt())
                } else {
                    ([0.80, 0.83, 0.88], [0.34, 0.32, 0.30], (-y).sqrt())
                };
                std::array::from_fn(|i| from[i] + (to[i] - from[i]) * t)
            }
        }
    }
}

/// How to render a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel along each axis: `samples²` rays on a regular grid within each pixel.
    pub samples: u32,
    /// Reflection and refraction bounces after the primary ray; at most [`MAX_BOUNCES`].
    pub max_depth: u32,
    /// Ambient light: irradiance every surface receives unshadowed.
    pub ambient: f64,
    pub background: Background,
}

impl Default for Settings {
    fn default() -> Self {
        Settings { width: 640, height: 480, samples: 2, max_depth: 5, ambient: 0.06, background: Background::Sky }
    }
}

/// Rays traced, by what they were for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounts {
    pub primary: u64,
    pub shadow: u64,
    pub reflection: u64,
    pub refraction: u64,
}

impl RayCounts {
    pub fn total(&self) -> u64 {
        self.primary + self.shadow + self.reflection + self.refraction
    }

    fn add(&mut self, o: &RayCounts) {
        self.primary += o.primary;
        self.shadow += o.shadow;
        self.reflection += o.reflection;
        self.refraction += o.refraction;
    }
}

/// A rendered frame: linear RGB per pixel (row by row from the top left), the work of every
/// query made for each pixel, and totals.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    pub color: Vec<[f32; 3]>,
    pub work: Vec<TraceStats>,
    pub rays: RayCounts,
    pub total_work: TraceStats,
}

impl Frame {
    /// The bytes of a frame of `width × height` pixels: the colours and the work counts that
    /// [`render`] allocates before it traces, for a caller to check against the memory it has.
    pub fn bytes(width: u32, height: u32) -> u64 {
        let per_pixel = (size_of::<[f32; 3]>() + size_of::<TraceStats>()) as u64;
        (width as u64 * height as u64).saturating_mul(per_pixel)
    }
}

/// The largest `max_depth` honoured: rays are traced by recursion, and facing mirrors or total
/// internal reflection keep a ray's weight up, so the depth alone bounds the stack.
pub const MAX_BOUNCES: u32 = 64;

/// Rays whose weight falls below this (per colour channel) are not traced.
const MIN_WEIGHT: f64 = 1.0 / 512.0;

#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Primary,
    Reflection,
    Refraction,
}

/// One pixel's tracing: the scene, and the counters its rays add to. Every position is relative
/// to `frame`, the tracer's origin, and every ray is a local one (`Intersector::origin`).
struct Tracing<'a, T: Intersector + ?Sized> {
    tracer: &'a T,
    scene: &'a Scene,
    frame: V3,
    /// The lights, positioned relative to `frame`.
    lights: &'a [Light],
    settings: &'a Settings,
    epsilon: f64,
    work: TraceStats,
    rays: RayCounts,
}

impl<T: Intersector + ?Sized> Tracing<'_, T> {
    /// The light arriving along `ray` (whose unit direction in f64 is `dir`).
    fn radiance(&mut self, ray: &Ray, dir: V3, depth: u32, weight: V3, kind: Kind) -> V3 {
        match kind {
            Kind::Primary => self.rays.primary += 1,
            Kind::Reflection => self.rays.reflection += 1,
            Kind::Refraction => self.rays.refraction += 1,
        }
        let Some(hit) = self.tracer.closest_hit_local_counted(ray, &mut self.work) else {
            return self.settings.background.colour(dir);
        };
        let Some(sp) = self.scene.surface_point(hit.prim, hit.u, hit.v, self.frame) else {
            return self.settings.background.colour(dir);
        };
        let s = sp.surface;
        // Normals facing the incoming ray (triangles are two-sided).
        let entering = dot(dir, sp.wound_normal) < 0.0;
        let side = if entering { 1.0 } else { -1.0 };
        let ng = scale(sp.wound_normal, side);
        let n = scale(sp.shading_normal, side);
        let view = scale(dir, -1.0);
        let above = madd(sp.point, ng, self.epsilon);
        let below = madd(sp.point, ng, -self.epsilon);

        let mut colour = add(s.emission, scale(s.diffuse, self.settings.ambient));
        let lit = max_component(s.diffuse) > 0.0 || max_component(s.specular) > 0.0;
        for light in self.lights.iter().filter(|_| lit) {
            let Some(inc) = light.incident(sp.point) else { continue };
            let cos = dot(n, inc.to_light);
            if cos <= 0.0 || dot(ng, inc.to_light) <= 0.0 {
                continue;
            }
            let shadow = Ray::with_interval(
                above.map(|c| c as f32),
                inc.to_light.map(|c| c as f32),
                0.0,
                (inc.distance - 2.0 * self.epsilon) as f32,
            );
            self.rays.shadow += 1;
            if self.tracer.any_hit_local_counted(&shadow, &mut self.work).is_some() {
                continue;
            }
            let highlight = dot(reflect(scale(inc.to_light, -1.0), n), view).max(0.0).powf(s.shininess);
            let local: V3 = std::array::from_fn(|i| s.diffuse[i] * cos + s.specular[i] * highlight);
            colour = add(colour, mul(local, inc.irradiance));
        }

        if depth >= self.settings.max_depth.min(MAX_BOUNCES) {
            return colour;
        }
        let mut kr = s.reflection;
        let mut kt = s.transmission;
        let mut refracted = None;
        if max_component(kt) > 0.0 {
            let eta = if entering { 1.0 / s.ior } else { s.ior };
            // Across the shading normal; across the geometric one if that would leave the ray on
            // the near side of the surface.
            let bent = match refract(dir, n, eta) {
                Some(b) if dot(b.0, ng) < 0.0 => Some(b),
                Some(_) => refract(dir, ng, eta).filter(|b| dot(b.0, ng) < 0.0),
                None => None,
            };
            match bent {
                // Total internal reflection.
                None => {
                    kr = add(kr, kt);
                    kt = [0.0; 3];
                }
                Some((t, cos_i, cos_t)) => {
                    // Schlick, with the cosine on the optically thinner side.
                    let r0 = ((s.ior - 1.0) / (s.ior + 1.0)).powi(2);
                    let c = 1.0 - if eta <= 1.0 { cos_i } else { cos_t };
                    let fresnel = r0 + (1.0 - r0) * c.powi(5);
                    kr = madd(kr, kt, fresnel);
                    kt = scale(kt, 1.0 - fresnel);
                    refracted = Some(t);
                }
            }
        }
        let wr = mul(weight, kr);
        if max_component(wr) >= MIN_WEIGHT {
            let r = Some(reflect(dir, n)).filter(|r| dot(*r, ng) > 0.0).unwrap_or_else(|| reflect(dir, ng));
            if let Some(r) = normalize(r) {
                let ray = Ray::new(above.map(|c| c as f32), r.map(|c| c as f32));
                let l = self.radiance(&ray, r, depth + 1, wr, Kind::Reflection);
                colour = add(colour, mul(kr, l));
            }
        }
        let wt = mul(weight, kt);
        if let Some(t) = refracted.filter(|_| max_component(wt) >= MIN_WEIGHT) {
            let ray = Ray::new(below.map(|c| c as f32), t.map(|c| c as f32));
            let l = self.radiance(&ray, t, depth + 1, wt, Kind::Refraction);
            colour = add(colour, mul(kt, l));
        }
        colour
    }
}

/// The direction of unit `d` refracted through a surface with unit normal `n` (facing against
/// `d`) and ratio of refractive indices `eta = n_from / n_to` (Snell's law), with the cosines of
/// the incident and refracted angles; `None` on total internal reflection.
fn refract(d: V3, n: V3, eta: f64) -> Option<(V3, f64, f64)> {
    let cos_i = (-dot(d, n)).min(1.0);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    if k < 0.0 {
        return None;
    }
    let cos_t = k.sqrt();
    normalize(madd(scale(d, eta), n, eta * cos_i - cos_t)).map(|t| (t, cos_i, cos_t))
}

/// Renders a frame of `scene` seen through `view` under `lights`, tracing with `tracer` on all of
/// rayon's threads (the global pool, or one installed around the call). `progress(rows)` is
/// called as rows finish.
///
/// Rays are traced relative to the tracer's origin (`Intersector::origin`, a field's centre):
/// the eye, the hit points and the lights are moved there in f64 before any ray is rounded to
/// f32, so a scene far from the world's origin is drawn with the precision of its own size.
pub fn render<T: Intersector + ?Sized>(
    tracer: &T,
    scene: &Scene,
    view: &View,
    lights: &[Light],
    settings: &Settings,
    progress: &(dyn Fn(u64) + Sync),
) -> Frame {
    let (width, height) = (settings.width as usize, settings.height as usize);
    let samples = settings.samples.max(1);
    let mut color = vec![[0.0f32; 3]; width * height];
    let mut work = vec![TraceStats::default(); width * height];
    let frame = tracer.origin();
    let lights: Vec<Light> = lights.iter().map(|l| l.relative_to(frame)).collect();
    let lights = &lights[..];
    let epsilon = scene.epsilon(frame);
    let per_pixel = 1.0 / (samples * samples) as f64;
    let (rays, total_work) = color
        .par_chunks_mut(width.max(1))
        .zip(work.par_chunks_mut(width.max(1)))
        .enumerate()
        .map(|(y, (row, row_work))| {
            let mut rays = RayCounts::default();
            let mut total = TraceStats::default();
            for (x, (pixel, pixel_work)) in row.iter_mut().zip(row_work.iter_mut()).enumerate() {
                let mut t = Tracing {
                    tracer,
                    scene,
                    frame,
                    lights,
                    settings,
                    epsilon,
                    work: TraceStats::default(),
                    rays: RayCounts::default(),
                };
                let mut sum = [0.0; 3];
                for j in 0..samples {
                    for i in 0..samples {
                        let fx = (x as f64 + (i as f64 + 0.5) / samples as f64) / width as f64;
                        let fy = (y as f64 + (j as f64 + 0.5) / samples as f64) / height as f64;
                        let ray = view.ray_relative_to(frame, fx, fy);
                        let dir = normalize(widen(ray.dir)).unwrap_or(view.forward);
                        sum = add(sum, t.radiance(&ray, dir, 0, [1.0; 3], Kind::Primary));
                    }
                }
                *pixel = scale(sum, per_pixel).map(|c| c as f32);
                *pixel_work = t.work;
                rays.add(&t.rays);
                total.add(&t.work);
            }
            progress(1);
            (rays, total)
        })
        .reduce(
            || (RayCounts::default(), TraceStats::default()),
            |(mut ra, mut wa), (rb, wb)| {
                ra.add(&rb);
                wa.add(&wb);
                (ra, wa)
            },
        );
    Frame { width: settings.width, height: settings.height, color, work, rays, total_work }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::length;

    fn close(a: V3, b: V3) -> bool {
        (0..3).all(|i| (a[i] - b[i]).abs() < 1e-12)
    }

    /// Snell's law: straight through at normal incidence, sines in the ratio of the indices at an
    /// angle, and total internal reflection past the critical angle going out of glass.
    #[test]
    fn refraction_follows_snells_law() {
        let n = [0.0, 1.0, 0.0];
        let (t, cos_i, cos_t) = refract([0.0, -1.0, 0.0], n, 1.0 / 1.5).unwrap();
        assert!(close(t, [0.0, -1.0, 0.0]) && cos_i == 1.0 && cos_t == 1.0);
        let d = normalize([1.0, -1.0, 0.0]).unwrap();
        let (t, _, _) = refract(d, n, 1.0 / 1.5).unwrap();
        let (sin_i, sin_t) = (d[0], t[0]);
        assert!((sin_i / sin_t - 1.5).abs() < 1e-12, "{sin_i} / {sin_t}");
        assert!(t[1] < 0.0 && (length(t) - 1.0).abs() < 1e-12);
        // Critical angle out of glass: asin(1/1.5) = 41.8°; 45° reflects totally, 40° does not.
        let out = |degrees: f64| {
            let a = degrees.to_radians();
            refract([a.sin(), -a.cos(), 0.0], n, 1.5)
        };
        assert!(out(45.0).is_none() && out(40.0).is_some());
    }
}
