//! Every contestant's answers against the brute force (`vlf_geom::BruteForce`: every triangle,
//! the field's watertight kernel) on a sample of each ray set.

use super::contestant::{Contestant, PeerHit};
use super::model::{Counts, Query, Tri};
use super::rays::RaySet;
use rayon::prelude::*;
use vlf_geom::{BruteForce, Intersector, Ray};

/// The brute force's answers on the sampled rays.
pub enum Reference {
    Closest(Vec<Option<PeerHit>>),
    Any(Vec<bool>),
}

/// The sampled rays of one set and the brute force's answers to them.
pub struct Checked {
    pub rays: Vec<Ray>,
    pub reference: Reference,
}

impl Checked {
    /// Traces `indices` of `set` by brute force over `tris`, stored relative to `origin` as the
    /// field stores them (all cores).
    pub fn new(tris: &[Tri], origin: [f64; 3], set: &RaySet, indices: &[usize]) -> Checked {
        let bf = BruteForce::relative(tris, origin);
        let rays: Vec<Ray> = indices.iter().map(|&i| set.rays[i]).collect();
        let reference = match set.query {
            Query::Closest => Reference::Closest(
                rays.par_iter()
                    .with_min_len(8)
                    .map(|r| bf.closest_hit(r).map(|h| PeerHit { t: h.t, prim: h.prim }))
                    .collect(),
            ),
            Query::Any => Reference::Any(rays.par_iter().with_min_len(8).map(|r| bf.any_hit(r)).collect()),
        };
        Checked { rays, reference }
    }

    /// How `c`'s answers compare; `tolerance` is the relative `t` difference still counted close.
    pub fn compare(&self, c: &dyn Contestant, tolerance: f64) -> Counts {
        let mut k = Counts { contestant: c.name().into(), rays: self.rays.len(), ..Counts::default() };
        match &self.reference {
            Reference::Closest(expected) => {
                let mut got = vec![None; self.rays.len()];
                c.closest_hits(&self.rays, &mut got);
                for (g, e) in got.iter().zip(expected) {
                    match (g, e) {
                        (None, None) => k.same += 1,
                        (Some(_), None) => k.extra_hits += 1,
                        (None, Some(_)) => k.missed += 1,
                        (Some(g), Some(e)) if g.t.to_bits() == e.t.to_bits() => {
                            if g.prim == e.prim {
                                k.same += 1
                            } else {
                                k.ties += 1
                            }
                        }
                        (Some(g), Some(e)) => {
                            let rel = (g.t as f64 - e.t as f64).abs() / (e.t as f64).abs().max(f64::MIN_POSITIVE);
                            if rel <= tolerance {
                                k.t_close += 1;
                                if g.prim != e.prim {
                                    k.other_prim_close += 1;
                                }
                            } else {
                                k.t_far += 1;
                            }
                        }
                    }
                }
            }
            Reference::Any(expected) => {
                let mut got = vec![false; self.rays.len()];
                c.any_hits(&self.rays, &mut got);
                for (&g, &e) in got.iter().zip(expected) {
                    match (g, e) {
                        (true, false) => k.extra_hits += 1,
                        (false, true) => k.missed += 1,
                        _ => k.same += 1,
                    }
                }
            }
        }
        k
    }
}
