//! The ray query (paper §3.3 and §5), answered straight from the file bytes.
//!
//! 1. Clip the ray to the scene's box grown by the margin `μ`. (Clipping it to the bounding
//!    sphere as well measured no faster: `docs/benchmarks/where-the-time-goes.md`.)
//! 2. Choose the stored direction nearest the ray's by the constant-time lattice lookup, and rotate
//!    the ray into that direction's canonical frame.
//! 3. Walk, front to back, every tile its projection crosses (Amanatides and Woo 1987 in the
//!    tile grid; the paper's Figure 2: a ray not parallel to the beams crosses several tiles).
//! 4. In each tile, visit the leaves of its block (`formats/vlf.md` §5.6) that the ray's z range
//!    passes through, in ray order. A leaf's refs are first tested by their quantized boxes
//!    against the ray's box over the leaf (sixteen at a time, [`crate::filter`]); only those that
//!    pass reach the watertight triangle kernel.
//! 5. Stop as soon as the best hit lies within the part of the ray already searched.
//!
//! Steps 1 and 2 are [`crate::setup`]; steps 3 to 5 the single-ray walk of [`crate::trace`] (and,
//! for several rays at once, the cursor of [`crate::walk`] that [`crate::batch`] runs). This
//! module holds the view and the queries' entry points, each compiled for every instruction set
//! of [`InstructionSet`] and run with the widest the CPU has.
//!
//! Triangles are stored relative to the scene's centre, and the ray is moved there first (in f64),
//! so a scene far from the world's origin keeps its precision ([`FieldView::closest_hit_local`]
//! takes rays already given relative to it).
//!
//! Geometry up to the triangle test is in f64, so its rounding stays far below the margin `μ` by
//! which the baker grew every footprint, z range and box (`formats/vlf.md` §6.2): the walk can only
//! see *more* candidates than the exact one, never fewer. Every index read from the file is
//! bounds-checked where it is used, so a file that passed the open checks but lies inside a section
//! yields wrong answers at worst, never a panic, an out-of-bounds read or unbounded work.

// Comparisons are written `!(a <= b)` on purpose throughout: a NaN (from a lying file) then takes
// the reject branch.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::filter::Passing;
use crate::setup::Aim;
use crate::trace::{AnySearch, ClosestSearch, trace};
use crate::walk::{Grid, Leaf, Setup, lower, walk_leaves};
use vlf_format::block::BOX_CELLS;
use vlf_format::{FieldReader, TriangleRecord};
use vlf_geom::{Avx2, Avx512, Baseline, Closest, Counter, Hit, Intersector, Isa, Ray, TraceStats, TriRay, Triangles};

/// The field's TRIANGLES section as the leaf kernel reads it.
pub(crate) struct FieldTriangles<'a>(pub(crate) &'a [TriangleRecord]);

impl Triangles for FieldTriangles<'_> {
    #[inline(always)]
    fn vertices(&self, id: u32) -> Option<&[[f32; 3]; 3]> {
        Some(&self.0.get(id as usize)?.v)
    }

    #[inline(always)]
    fn count(&self) -> usize {
        self.0.len()
    }
}

/// The validated field plus the constants every query needs, derived once at open.
#[derive(Clone, Copy, Debug)]
pub struct FieldView<'a> {
    pub(crate) reader: FieldReader<'a>,
    pub(crate) grid: Grid,
    /// Steps 1 and 2's constants and tables.
    aim: Aim<'a>,
    center: [f64; 3],
    /// The widest instructions the CPU has, which the single-ray queries are compiled for.
    isa: Tier,
}

/// An instruction set the single-ray queries are compiled for. Every one gives the same answers,
/// bit for bit; they differ in speed only ([`FieldView::with_instruction_set`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum InstructionSet {
    /// What every CPU of the target has: SSE2 on x86-64 (two triangles per vector), plain
    /// scalar code elsewhere.
    Baseline,
    /// x86-64 with AVX2, BMI1, BMI2, LZCNT and POPCNT (x86-64-v3): four triangles per vector.
    Avx2,
    /// x86-64-v3 with AVX-512 F, VL, BW and DQ: the same kernel, with twice the vector registers.
    Avx512,
}

impl InstructionSet {
    /// Its name: `baseline`, `avx2` or `avx512` (the values of `VLF_ISA`).
    pub fn name(self) -> &'static str {
        match self {
            InstructionSet::Baseline => "baseline",
            InstructionSet::Avx2 => "avx2",
            InstructionSet::Avx512 => "avx512",
        }
    }

    /// The instruction set named `name` (`baseline`, `avx2` or `avx512`).
    pub fn from_name(name: &str) -> Option<InstructionSet> {
        [InstructionSet::Baseline, InstructionSet::Avx2, InstructionSet::Avx512].into_iter().find(|i| i.name() == name)
    }

    /// Every instruction set this CPU supports, narrowest first.
    pub fn supported() -> Vec<InstructionSet> {
        [InstructionSet::Baseline, InstructionSet::Avx2, InstructionSet::Avx512]
            .into_iter()
            .filter(|&i| Tier::widest(i).set() == i)
            .collect()
    }
}

/// The instruction sets the single-ray queries are compiled for, each with the token that proves
/// the CPU has it.
#[derive(Clone, Copy, Debug)]
enum Tier {
    Avx512(Avx512),
    Avx2(Avx2),
    Baseline,
}

impl Tier {
    /// The widest tier this CPU supports, up to `cap`.
    fn widest(cap: InstructionSet) -> Tier {
        match (Avx512::detect(), Avx2::detect()) {
            (Some(isa), _) if cap >= InstructionSet::Avx512 => Tier::Avx512(isa),
            (_, Some(isa)) if cap >= InstructionSet::Avx2 => Tier::Avx2(isa),
            _ => Tier::Baseline,
        }
    }

    /// The widest tier this CPU supports, up to the one `VLF_ISA` names if it is set.
    fn detect() -> Tier {
        let cap = std::env::var("VLF_ISA").ok().and_then(|name| InstructionSet::from_name(&name));
        Tier::widest(cap.unwrap_or(InstructionSet::Avx512))
    }

    fn set(self) -> InstructionSet {
        match self {
            Tier::Avx512(_) => InstructionSet::Avx512,
            Tier::Avx2(_) => InstructionSet::Avx2,
            Tier::Baseline => InstructionSet::Baseline,
        }
    }
}

impl<'a> FieldView<'a> {
    pub(crate) fn new(reader: FieldReader<'a>) -> Self {
        let p = reader.params;
        let s = reader.scene;
        let n = p.tile_resolution as usize;
        let tile_width = 2.0 * s.radius / n as f64;
        FieldView {
            reader,
            grid: Grid {
                n,
                radius: s.radius,
                tile_width,
                inv_tile_width: 1.0 / tile_width,
                cells_per_unit: BOX_CELLS as f64 / tile_width,
                margin: p.margin,
            },
            aim: Aim::new(&reader),
            center: s.center,
            isa: Tier::detect(),
        }
    }

    /// The instruction set the single-ray queries run with: the widest this CPU supports, or
    /// narrower if the environment variable `VLF_ISA` (`baseline`, `avx2`, `avx512`) asked for it
    /// when the field was opened.
    pub fn instruction_set(&self) -> InstructionSet {
        self.isa.set()
    }

    /// This view with its single-ray queries run with at most `cap` (the widest this CPU supports
    /// otherwise): the answers are the same, bit for bit, only the speed differs. For comparing
    /// them, or for CPUs that slow their clock down for wide vectors.
    pub fn with_instruction_set(mut self, cap: InstructionSet) -> Self {
        self.isa = Tier::widest(cap);
        self
    }

    /// The point the field's triangles are stored relative to: the centre of its scene, in world
    /// coordinates.
    pub fn origin(&self) -> [f64; 3] {
        self.center
    }

    /// The stored direction for ray direction `d` and the sign (+1 or −1) that makes the beam
    /// direction point the same way as `d`: the lattice direction nearest to `d`
    /// (`formats/vlf.md` §5.3). Constant time: one division and two table reads. `None` only if
    /// the file's lookup table lies (points at no stored direction).
    ///
    /// For lattices of up to eight segments (129 directions) the nearest lattice point is read
    /// from a table built into the runtime, which holds it for the centre of each square of `1/8`
    /// of a segment of the octahedron's face (so the choice can differ from the exact one only
    /// for directions near the boundary between two lattice points, where both are about as
    /// near); finer lattices compare the dot products of the three nearest candidates.
    #[inline]
    pub fn select_direction(&self, d: [f64; 3]) -> Option<(usize, f64)> {
        self.aim.select_direction(d)
    }

    /// Steps 1 and 2 for a ray whose origin is given relative to `origin` (the world's origin for
    /// world rays: the ray is moved to the centre here).
    #[inline(always)]
    pub(crate) fn setup(&self, ray: &Ray, origin: [f64; 3]) -> Option<Setup> {
        self.aim.setup(ray, origin)
    }

    /// The closest hit on `[tmin, tmax]` of a ray in world coordinates, or `None`:
    /// [`crate::Field::closest_hit`].
    #[inline]
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.closest_hit_counted(ray, &mut ())
    }

    /// [`Self::closest_hit`], counting the work done in `counter` (rays, tiles, leaves and
    /// triangle tests; `()` counts nothing).
    pub fn closest_hit_counted(&self, ray: &Ray, counter: &mut impl Counter) -> Option<Hit> {
        self.closest(ray, self.center, counter)
    }

    /// The closest hit of a ray whose origin is given relative to [`Self::origin`] (the
    /// scene's centre): for scenes far from the world's origin, where an f32 world origin
    /// cannot be precise. `t`, `u`, `v` and `prim` mean what they mean for world rays.
    #[inline]
    pub fn closest_hit_local(&self, ray: &Ray) -> Option<Hit> {
        self.closest_hit_local_counted(ray, &mut ())
    }

    /// [`Self::closest_hit_local`], counting the work done in `counter`.
    pub fn closest_hit_local_counted(&self, ray: &Ray, counter: &mut impl Counter) -> Option<Hit> {
        self.closest(ray, [0.0; 3], counter)
    }

    /// Whether anything is hit on `[tmin, tmax]`; the first hit found ends the search:
    /// [`crate::Field::any_hit`].
    #[inline]
    pub fn any_hit(&self, ray: &Ray) -> bool {
        self.any_hit_counted(ray, &mut ()).is_some()
    }

    /// The first hit found on `[tmin, tmax]` (not necessarily the closest), counting the work:
    /// the walk of [`Self::closest_hit`], ordered as [`crate::Field::any_hit`] says.
    pub fn any_hit_counted(&self, ray: &Ray, counter: &mut impl Counter) -> Option<Hit> {
        self.any(ray, self.center, counter)
    }

    /// [`Self::any_hit`] for a ray given relative to [`Self::origin`].
    #[inline]
    pub fn any_hit_local(&self, ray: &Ray) -> bool {
        self.any_hit_local_counted(ray, &mut ()).is_some()
    }

    /// [`Self::any_hit_counted`] for a ray given relative to [`Self::origin`].
    pub fn any_hit_local_counted(&self, ray: &Ray, counter: &mut impl Counter) -> Option<Hit> {
        self.any(ray, [0.0; 3], counter)
    }

    #[inline(always)]
    fn closest(&self, ray: &Ray, origin: [f64; 3], counter: &mut impl Counter) -> Option<Hit> {
        self.closest_with(ray, origin, &FieldTriangles(self.reader.triangles), counter)
    }

    #[inline(always)]
    fn any(&self, ray: &Ray, origin: [f64; 3], counter: &mut impl Counter) -> Option<Hit> {
        self.any_with(ray, origin, &FieldTriangles(self.reader.triangles), counter)
    }

    /// The closest hit of a ray given relative to `origin`, with the triangles read through
    /// `tris`: steps 1 to 5, compiled for the widest instruction set the CPU has
    /// ([`Self::dispatch`]). A function of its own so that profiles (and
    /// `docs/benchmarks/against-embree.sh`) can count the query's instructions by its name.
    #[inline(never)]
    fn closest_with(
        &self,
        ray: &Ray,
        origin: [f64; 3],
        tris: &impl Triangles,
        counter: &mut impl Counter,
    ) -> Option<Hit> {
        self.dispatch::<ClosestQuery>(ray, origin, tris, counter)
    }

    /// The first hit found of a ray given relative to `origin`, with the triangles read through
    /// `tris`, compiled as [`Self::closest_with`] is.
    #[inline(never)]
    fn any_with(&self, ray: &Ray, origin: [f64; 3], tris: &impl Triangles, counter: &mut impl Counter) -> Option<Hit> {
        self.dispatch::<AnyQuery>(ray, origin, tris, counter)
    }

    /// Runs the query `Q` compiled for the view's instruction set: a test and a call. (The
    /// baseline body is a function of its own too: inlined here, every query paid its stack
    /// frame, 2 KiB, and six register saves before calling the AVX2 body, 14 instructions a ray.)
    #[inline(always)]
    fn dispatch<Q: Query>(
        &self,
        ray: &Ray,
        origin: [f64; 3],
        tris: &impl Triangles,
        counter: &mut impl Counter,
    ) -> Option<Hit> {
        #[cfg(target_arch = "x86_64")]
        match self.isa {
            // SAFETY: `Avx512` exists only if the CPU supports AVX-512 F, VL, BW and DQ and AVX2
            // (`Avx512::detect`), which is what `run_avx512` is compiled for; BMI1, BMI2, LZCNT
            // and POPCNT come with every CPU that has AVX2 (x86-64-v3).
            Tier::Avx512(isa) => return unsafe { self.run_avx512::<Q>(isa, ray, origin, tris, counter) },
            // SAFETY: `Avx2` exists only if the CPU supports AVX2 (`Avx2::detect`), which is what
            // `run_avx2` is compiled for, with BMI1, BMI2, LZCNT and POPCNT as above.
            Tier::Avx2(isa) => return unsafe { self.run_avx2::<Q>(isa, ray, origin, tris, counter) },
            Tier::Baseline => {}
        }
        self.run_baseline::<Q>(ray, origin, tris, counter)
    }

    #[inline(never)]
    fn run_baseline<Q: Query>(
        &self,
        ray: &Ray,
        origin: [f64; 3],
        tris: &impl Triangles,
        counter: &mut impl Counter,
    ) -> Option<Hit> {
        Q::run(self, Baseline, ray, origin, tris, counter)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt,avx512f,avx512vl,avx512bw,avx512dq")]
    fn run_avx512<Q: Query>(
        &self,
        isa: Avx512,
        ray: &Ray,
        origin: [f64; 3],
        tris: &impl Triangles,
        counter: &mut impl Counter,
    ) -> Option<Hit> {
        Q::run(self, isa, ray, origin, tris, counter)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    fn run_avx2<Q: Query>(
        &self,
        isa: Avx2,
        ray: &Ray,
        origin: [f64; 3],
        tris: &impl Triangles,
        counter: &mut impl Counter,
    ) -> Option<Hit> {
        Q::run(self, isa, ray, origin, tris, counter)
    }

    /// [`Self::closest_hit_local`] with the triangles read through `tris` instead of the field's
    /// TRIANGLES, counting the work: an id whose `tris.vertices(id)` is `None` is skipped, as the
    /// kernel skips ids a damaged file names. For callers that hide some of a field's triangles
    /// without writing its bytes (`vlf-scene`'s edits). The walk is [`Self::closest_hit`]'s.
    pub fn closest_hit_local_in(&self, ray: &Ray, tris: &impl Triangles, counter: &mut impl Counter) -> Option<Hit> {
        self.closest_with(ray, [0.0; 3], tris, counter)
    }

    /// [`Self::any_hit_local`] with the triangles read through `tris`, as
    /// [`Self::closest_hit_local_in`]; the first hit found, counting the work.
    pub fn any_hit_local_in(&self, ray: &Ray, tris: &impl Triangles, counter: &mut impl Counter) -> Option<Hit> {
        self.any_with(ray, [0.0; 3], tris, counter)
    }

    /// The ray's candidate set (the paper's potentially visible set), leaf by leaf in ray order:
    /// calls `visit(ids, exit_t)` with the triangle ids of each visited leaf (before the box test)
    /// and the ray parameter at which the ray leaves that leaf, until `visit` returns `true`. A
    /// triangle may appear in several leaves. This is the walk [`Self::closest_hit`] does, without
    /// the box and triangle tests.
    pub fn for_each_leaf(&self, ray: &Ray, counter: &mut impl Counter, mut visit: impl FnMut(&[u32], f64) -> bool) {
        let Some(setup) = self.setup(ray, self.center) else { return };
        walk_leaves(&self.reader, &self.grid, &setup, counter, |leaf, _| visit(leaf.ids(), leaf.exit_t));
    }

    /// The walk of the all-hits query (`crate::all_hits`): calls `visit(passing, exit_t)` for each
    /// leaf along the ray, front to back, until it returns `true`; `passing(t_far)` gives the ids
    /// of the leaf's refs whose boxes meet the ray's box over `[enter_t, t_far]`, as
    /// [`Self::closest_hit`] tests them.
    pub(crate) fn for_each_leaf_filtered(
        &self,
        ray: &Ray,
        mut visit: impl FnMut(&dyn Fn(f64) -> Passing<'a>, f64) -> bool,
    ) {
        let Some(setup) = self.setup(ray, self.center) else { return };
        walk_leaves(&self.reader, &self.grid, &setup, &mut (), |leaf, _| {
            visit(&|t_far| leaf.passing(t_far, &[]), leaf.exit_t)
        });
    }
}

/// A single-ray query, steps 1 to 5 for one instruction set: what [`FieldView::dispatch`] runs.
trait Query {
    fn run<'t>(
        view: &FieldView<'_>,
        isa: impl Isa,
        ray: &Ray,
        origin: [f64; 3],
        tris: &'t (impl Triangles + 't),
        counter: &mut impl Counter,
    ) -> Option<Hit>;
}

/// The closest hit ([`FieldView::closest_hit`]).
struct ClosestQuery;

impl Query for ClosestQuery {
    #[inline(always)]
    fn run<'t>(
        view: &FieldView<'_>,
        isa: impl Isa,
        ray: &Ray,
        origin: [f64; 3],
        tris: &'t (impl Triangles + 't),
        counter: &mut impl Counter,
    ) -> Option<Hit> {
        let setup = view.setup(ray, origin)?;
        counter.ray();
        let mut search = ClosestSearch { isa, ray: TriRay::relative(ray, origin), tris, best: Closest::new(ray.tmax) };
        trace(&view.reader, &view.grid, &setup, &mut search, counter);
        search.best.hit
    }
}

/// The first hit found ([`FieldView::any_hit`]); a segment that leaves the scene is walked from
/// its far end, and a segment that starts inside puts off its origin leaf
/// ([`crate::walk::Setup::for_any_hit`]).
struct AnyQuery;

impl Query for AnyQuery {
    #[inline(always)]
    fn run<'t>(
        view: &FieldView<'_>,
        isa: impl Isa,
        ray: &Ray,
        origin: [f64; 3],
        tris: &'t (impl Triangles + 't),
        counter: &mut impl Counter,
    ) -> Option<Hit> {
        let (setup, defer_origin) = view.setup(ray, origin)?.for_any_hit(ray.tmax as f64, view.grid.radius);
        counter.ray();
        let ray = TriRay::relative(ray, origin);
        if defer_origin {
            any_walk::<true>(view, AnySearch { isa, ray, tris, found: None }, &setup, counter)
        } else {
            any_walk::<false>(view, AnySearch { isa, ray, tris, found: None }, &setup, counter)
        }
    }
}

/// Runs `search` over the walk of `setup`; the first hit found.
#[inline(always)]
fn any_walk<'t, const DEFER: bool>(
    view: &FieldView<'_>,
    mut search: AnySearch<'t, impl Isa, impl Triangles + 't, DEFER>,
    setup: &Setup,
    counter: &mut impl Counter,
) -> Option<Hit> {
    trace(&view.reader, &view.grid, setup, &mut search, counter);
    search.found
}

/// The refs of `leaf` the closest-hit search tests: those whose boxes meet the ray over the
/// part of the leaf before the best hit so far; `load` as for [`Leaf::passing`].
#[inline(always)]
pub(crate) fn closest_refs<'a>(leaf: &Leaf<'a>, best: &Closest, load: &'a [TriangleRecord]) -> Passing<'a> {
    leaf.passing(lower(leaf.exit_t, best.tmax as f64), load)
}

/// Step 4 for the closest hit: tests `refs` ([`closest_refs`] of a leaf the ray leaves at
/// `exit_t`), keeping the closest hit in `best`. Returns whether the search is over: the best hit
/// lies within the part of the ray already searched.
#[inline(always)]
pub(crate) fn closest_in_refs(
    tri_ray: &TriRay,
    tris: &impl Triangles,
    refs: Passing<'_>,
    exit_t: f64,
    best: &mut Closest,
    counter: &mut impl Counter,
) -> bool {
    tri_ray.closest_in(Baseline, tris, refs, best, counter);
    best.hit.is_some() && (best.tmax as f64) <= exit_t
}

/// The queries above through the trait the renderer, tests and benchmarks share.
impl Intersector for FieldView<'_> {
    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        FieldView::closest_hit(self, ray)
    }
    fn any_hit(&self, ray: &Ray) -> bool {
        FieldView::any_hit(self, ray)
    }
    fn closest_hit_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        FieldView::closest_hit_counted(self, ray, work)
    }
    fn any_hit_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        FieldView::any_hit_counted(self, ray, work)
    }
    fn origin(&self) -> [f64; 3] {
        FieldView::origin(self)
    }
    fn closest_hit_local_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        FieldView::closest_hit_local_counted(self, ray, work)
    }
    fn any_hit_local_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        FieldView::any_hit_local_counted(self, ray, work)
    }
}
