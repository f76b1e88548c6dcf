//! Where the default outside camera stands: it frames the scene's bounding box (`Field::bounds`)
//! in both directions of the picture, whatever the picture's aspect ratio, with a small border.
//!
//! It looks from the paper's outside direction (Figure 3: from the centre towards `(0.45, 0.3, 1)`)
//! at the centre of the box, and stands as close as it can with every corner of the box inside
//! the picture: for each corner `p` (relative to the centre, in the camera's frame `x` right, `y`
//! up, `z` along the line of sight), `|x| ≤ (s + z)·tan(h/2)` and `|y| ≤ (s + z)·tan(v/2)` give
//! the least distance `s` in closed form. A wide scene is not cut at the sides of a tall picture,
//! and a scene smaller than its bounding sphere suggests fills the picture.
//!
//! A box so thin that from there it would cover under [`MIN_COVERAGE`] of the picture (a rod of
//! 1000 × 1 × 1 covers 0.1%: a line thinner than a pixel) is looked at along one of the world
//! axes instead, the one from which it covers the most (the rod: end on, about two thirds).

use crate::math::{V3, cross, dot, length, madd, normalize, scale, sub};

/// From the scene's centre towards the outside camera (the paper's Figure 3 viewpoint).
pub const OUTSIDE_DIRECTION: V3 = [0.45, 0.3, 1.0];
/// The outside camera's vertical field of view, in degrees.
pub const OUTSIDE_FOV_DEGREES: f64 = 50.0;
/// How far the framed box may reach towards the picture's edges: a border of 5%.
const MARGIN: f64 = 0.95;
/// The least share of the picture the box must cover from [`OUTSIDE_DIRECTION`] before an axis
/// view is tried.
pub const MIN_COVERAGE: f64 = 0.01;

/// A camera placement for a pinhole of [`OUTSIDE_FOV_DEGREES`]: eye, target, up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub eye: V3,
    pub target: V3,
    pub up: V3,
    /// The share of the picture the box covers, 0 to 1.
    pub coverage: f64,
}

/// The outside camera's placement for the box `min..max` and a picture of aspect `width /
/// height` (see the module documentation); `None` if the box is not a finite box of some size (a
/// damaged field), for the caller to fall back on the bounding sphere.
pub fn outside(min: V3, max: V3, aspect: f64) -> Option<Placement> {
    let valid = min.iter().chain(&max).all(|c| c.is_finite()) && (0..3).all(|i| min[i] <= max[i]);
    // `valid` makes the length finite; NaN aspects fail `is_finite`.
    if !valid || length(sub(max, min)) <= 0.0 || !aspect.is_finite() || aspect <= 0.0 {
        return None;
    }
    let default = place(min, max, OUTSIDE_DIRECTION, [0.0, 1.0, 0.0], aspect)?;
    if default.coverage >= MIN_COVERAGE {
        return Some(default);
    }
    let axes =
        [([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]), ([0.0, 0.0, 1.0], [0.0, 1.0, 0.0]), ([0.0, 1.0, 0.0], [0.0, 0.0, -1.0])];
    axes.iter()
        .filter_map(|&(direction, up)| place(min, max, direction, up, aspect))
        .chain([default])
        .max_by(|a, b| a.coverage.total_cmp(&b.coverage))
}

/// The closest placement looking from `direction` (centre → eye) at the centre of the box, with
/// every corner inside the picture's margin.
fn place(min: V3, max: V3, direction: V3, up: V3, aspect: f64) -> Option<Placement> {
    let center = scale(madd(min, max, 1.0), 0.5);
    let back = normalize(direction)?;
    let forward = scale(back, -1.0);
    let right = normalize(cross(forward, up))?;
    let image_up = cross(right, forward);
    let tan_v = (OUTSIDE_FOV_DEGREES.to_radians() / 2.0).tan();
    let tan_h = tan_v * aspect;
    let corners: Vec<V3> = (0..8)
        .map(|k| {
            sub(
                [
                    if k & 1 == 0 { min[0] } else { max[0] },
                    if k & 2 == 0 { min[1] } else { max[1] },
                    if k & 4 == 0 { min[2] } else { max[2] },
                ],
                center,
            )
        })
        .map(|p| [dot(right, p), dot(image_up, p), dot(forward, p)])
        .collect();
    // Every corner inside the margin, and a little in front of the eye.
    let near = 1e-3 * length(sub(max, min));
    let distance = corners
        .iter()
        .map(|&[x, y, z]| (x.abs() / (tan_h * MARGIN) - z).max(y.abs() / (tan_v * MARGIN) - z).max(near - z))
        .fold(0.0, f64::max);
    let projected: Vec<[f64; 2]> =
        corners.iter().map(|&[x, y, z]| [x / (distance + z) / tan_h, y / (distance + z) / tan_v]).collect();
    let coverage = hull_area(&projected) / 4.0;
    let eye = madd(center, back, distance);
    (distance.is_finite() && coverage.is_finite()).then_some(Placement { eye, target: center, up, coverage })
}

/// The area of the convex hull of `points` (Andrew's monotone chain, then the shoelace formula):
/// the picture area a convex box covers is the hull of its corners' images.
fn hull_area(points: &[[f64; 2]]) -> f64 {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    let turn = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
    let mut hull: Vec<[f64; 2]> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        for &q in &p {
            while hull.len() >= start + 2 && turn(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0 {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
        if pass == 0 {
            p.reverse();
        }
    }
    let n = hull.len();
    (0..n).map(|i| hull[i][0] * hull[(i + 1) % n][1] - hull[(i + 1) % n][0] * hull[i][1]).sum::<f64>().abs() / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The corners of the box in picture coordinates, `[-1, 1]` across the picture.
    fn corners_in_picture(min: V3, max: V3, aspect: f64, p: &Placement) -> Vec<[f64; 2]> {
        let forward = normalize(sub(p.target, p.eye)).unwrap();
        let right = normalize(cross(forward, p.up)).unwrap();
        let up = cross(right, forward);
        let tan_v = (OUTSIDE_FOV_DEGREES.to_radians() / 2.0).tan();
        (0..8)
            .map(|k| {
                let c = [[min[0], max[0]][k & 1], [min[1], max[1]][(k >> 1) & 1], [min[2], max[2]][(k >> 2) & 1]];
                let d = sub(c, p.eye);
                let z = dot(forward, d);
                assert!(z > 0.0, "a corner behind the eye");
                [dot(right, d) / z / (tan_v * aspect), dot(up, d) / z / tan_v]
            })
            .collect()
    }

    #[test]
    fn every_box_is_framed_tightly_in_both_directions_at_any_aspect() {
        let boxes = [
            ([-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]),
            ([-10.0, -1.0, -1.0], [10.0, 1.0, 1.0]),
            ([-1.0, -10.0, -1.0], [1.0, 10.0, 1.0]),
            ([-10.0, -0.1, -10.0], [10.0, 0.1, 10.0]),
            ([3.0, 5.0, -7.0], [4.0, 5.0, 9.0]),
            ([-500.0, -0.5, -0.5], [500.0, 0.5, 0.5]),
        ];
        for (min, max) in boxes {
            for aspect in [0.25, 0.75, 1.0, 4.0 / 3.0, 3.0] {
                let p = outside(min, max, aspect).unwrap();
                let corners = corners_in_picture(min, max, aspect, &p);
                let reach = |i: usize| corners.iter().map(|c| c[i].abs()).fold(0.0, f64::max);
                let (x, y) = (reach(0), reach(1));
                assert!(x <= MARGIN + 1e-9 && y <= MARGIN + 1e-9, "{min:?}..{max:?} at {aspect}: cropped ({x}, {y})");
                assert!(x.max(y) >= MARGIN - 1e-9, "{min:?}..{max:?} at {aspect}: not tight ({x}, {y})");
                assert!(p.coverage >= MIN_COVERAGE, "{min:?}..{max:?} at {aspect}: covers {}", p.coverage);
            }
        }
    }

    #[test]
    fn compact_boxes_are_seen_from_the_papers_direction_and_a_rod_end_on() {
        let cube = outside([-1.0; 3], [1.0; 3], 4.0 / 3.0).unwrap();
        let towards = normalize(sub(cube.eye, cube.target)).unwrap();
        assert!(length(sub(towards, normalize(OUTSIDE_DIRECTION).unwrap())) < 1e-12);
        assert!(cube.coverage > 0.3, "{}", cube.coverage);
        let rod = outside([-500.0, -0.5, -0.5], [500.0, 0.5, 0.5], 4.0 / 3.0).unwrap();
        assert_eq!(normalize(sub(rod.eye, rod.target)).unwrap(), [1.0, 0.0, 0.0]);
        assert!(rod.coverage > 0.6, "{}", rod.coverage);
        // From the paper's direction the rod would cover a thousandth of the picture.
        let side = place([-500.0, -0.5, -0.5], [500.0, 0.5, 0.5], OUTSIDE_DIRECTION, [0.0, 1.0, 0.0], 4.0 / 3.0);
        assert!(side.unwrap().coverage < MIN_COVERAGE);
    }

    #[test]
    fn damaged_boxes_have_no_placement() {
        for (min, max) in [([0.0; 3], [0.0; 3]), ([1.0, 0.0, 0.0], [0.0, 1.0, 1.0]), ([f64::NAN, 0.0, 0.0], [1.0; 3])] {
            assert_eq!(outside(min, max, 1.0), None);
        }
        assert_eq!(outside([0.0; 3], [1.0; 3], f64::NAN), None);
    }

    #[test]
    fn hull_areas() {
        let square = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0], [0.0, 0.0], [0.5, -0.2]];
        assert!((hull_area(&square) - 4.0).abs() < 1e-12);
        assert_eq!(hull_area(&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]), 0.0);
    }
}
