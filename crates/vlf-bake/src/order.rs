//! The order of a scene's triangles: along a Morton (Z-order) curve through their centroids, so
//! that triangles close in space are close in TRIANGLES (`formats/vlf.md` §5.7).
//!
//! A query loads the triangles that pass a leaf's box test, and the rays of a view or a bounce
//! load the triangles of neighbouring leaves. In import order those can be anywhere in the
//! section (a random scene's are spread over all of it), each a miss of its own; in Morton order
//! a leaf's refs, which are sorted by id, point into a few runs of cache lines that neighbouring
//! rays share.

/// Bits per axis of the Morton code: 3 × 21 = 63.
const BITS: u32 = 21;

/// The permutation that puts `triangles` in Morton order of their centroids: entry `k` is the
/// index in `triangles` of the `k`-th triangle in the new order. Centroids are quantised to
/// 2²¹ steps per axis over their own box; triangles with the same code keep their relative order.
/// Deterministic: it depends on the vertices' bits only.
pub fn morton_order(triangles: &[[[f32; 3]; 3]]) -> Vec<u32> {
    let centroid = |t: &[[f32; 3]; 3]| -> [f64; 3] {
        std::array::from_fn(|i| (t[0][i] as f64 + t[1][i] as f64 + t[2][i] as f64) / 3.0)
    };
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for t in triangles {
        let c = centroid(t);
        for i in 0..3 {
            lo[i] = lo[i].min(c[i]);
            hi[i] = hi[i].max(c[i]);
        }
    }
    let steps = ((1u64 << BITS) - 1) as f64;
    let scale: [f64; 3] = std::array::from_fn(|i| if hi[i] > lo[i] { steps / (hi[i] - lo[i]) } else { 0.0 });
    let mut keyed: Vec<(u64, u32)> = triangles
        .iter()
        .enumerate()
        .map(|(k, t)| {
            let c = centroid(t);
            let q: [u64; 3] = std::array::from_fn(|i| ((c[i] - lo[i]) * scale[i]).clamp(0.0, steps) as u64);
            (spread(q[0]) | spread(q[1]) << 1 | spread(q[2]) << 2, k as u32)
        })
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, k)| k).collect()
}

/// The low 21 bits of `v`, each moved to bit `3i`.
fn spread(v: u64) -> u64 {
    let mut x = v & 0x1f_ffff;
    x = (x | x << 32) & 0x001f_0000_0000_ffff;
    x = (x | x << 16) & 0x001f_0000_ff00_00ff;
    x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
    x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
    x = (x | x << 2) & 0x1249_2492_4924_9249;
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `spread` by its definition, one bit at a time.
    fn spread_slow(v: u64) -> u64 {
        (0..BITS).fold(0, |acc, b| acc | ((v >> b) & 1) << (3 * b))
    }

    #[test]
    fn spread_moves_each_bit_to_three_times_its_place() {
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        for v in [0, 1, 2, 0x1f_ffff, 0x15_5555, 0x0a_aaaa] {
            assert_eq!(spread(v), spread_slow(v), "{v:#x}");
        }
        for _ in 0..1000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = x & 0x1f_ffff;
            assert_eq!(spread(v), spread_slow(v), "{v:#x}");
        }
    }

    fn tri(c: [f32; 3]) -> [[f32; 3]; 3] {
        [c, [c[0] + 0.01, c[1], c[2]], [c[0], c[1] + 0.01, c[2]]]
    }

    #[test]
    fn order_is_a_permutation_along_the_z_curve() {
        // The eight corners of a cube, given in reverse Morton order, come out in Morton order
        // (x the lowest bit, then y, then z).
        let corners: Vec<[[f32; 3]; 3]> =
            (0..8u32).rev().map(|m| tri([(m & 1) as f32, (m >> 1 & 1) as f32, (m >> 2 & 1) as f32])).collect();
        assert_eq!(morton_order(&corners), vec![7, 6, 5, 4, 3, 2, 1, 0]);
        // Equal centroids keep their order; every index appears once.
        let same = vec![tri([0.5; 3]); 5];
        assert_eq!(morton_order(&same), vec![0, 1, 2, 3, 4]);
        assert!(morton_order(&[]).is_empty());
    }
}
