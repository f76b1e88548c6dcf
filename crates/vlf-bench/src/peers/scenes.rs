//! The scenes of the peers benchmark: the paper's random triangles at a fixed size and at a size
//! that shrinks with the count, the bundled bunny, and meshes given by path (a real scan).

use anyhow::Context as _;
use std::path::{Path, PathBuf};
use vlf_bake::generate::{DEFAULT_TRIANGLE_SIZE, random_cube};

/// A triangle as every contestant takes it.
pub type Tri = [[f32; 3]; 3];

/// How the random triangles' size follows their count.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum SizeRule {
    /// Half-extent `DEFAULT_TRIANGLE_SIZE` = 0.05 whatever the count (the paper's scenes: more
    /// triangles, more depth complexity).
    Fixed,
    /// Half-extent `0.05 · (10⁴ / n)^(1/3)`: 0.05 at 10K, 0.0232 at 100K, 0.0108 at 1M. The
    /// triangles' total area grows as `n^(1/3)` instead of `n`, so a scene of more triangles is
    /// finer rather than much deeper.
    Density,
}

impl SizeRule {
    /// The half-extent of `n` triangles.
    pub fn size(self, n: usize) -> f64 {
        match self {
            SizeRule::Fixed => DEFAULT_TRIANGLE_SIZE,
            SizeRule::Density => DEFAULT_TRIANGLE_SIZE * (1e4 / n.max(1) as f64).cbrt(),
        }
    }

    fn tag(self) -> &'static str {
        match self {
            SizeRule::Fixed => "fixed",
            SizeRule::Density => "density",
        }
    }
}

/// A scene to run.
#[derive(Clone, Debug, serde::Serialize)]
pub enum SceneSpec {
    /// `random_cube(n, rule.size(n), seed 1)`.
    Random { triangles: usize, rule: SizeRule },
    /// A mesh file (OBJ or glTF) imported by `vlf_bake::import`.
    Mesh { path: PathBuf },
}

/// A loaded scene.
pub struct LoadedScene {
    pub name: String,
    pub description: String,
    pub triangles: Vec<Tri>,
}

/// `10K`, `100K`, `1M`-style counts.
pub fn short_count(n: usize) -> String {
    if n >= 1_000_000 && n.is_multiple_of(1_000_000) {
        format!("{}M", n / 1_000_000)
    } else if n >= 1000 && n.is_multiple_of(1000) {
        format!("{}K", n / 1000)
    } else {
        n.to_string()
    }
}

impl SceneSpec {
    /// The bundled bunny, `fixtures/meshes/bunny.obj` under the workspace root.
    pub fn bunny() -> SceneSpec {
        SceneSpec::Mesh { path: Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/meshes/bunny.obj") }
    }

    /// Loads (or generates) the triangles. Degenerate triangles of a mesh are dropped by the
    /// importer, so every contestant gets exactly the field's triangles, in its order.
    pub fn load(&self) -> anyhow::Result<LoadedScene> {
        match self {
            SceneSpec::Random { triangles, rule } => {
                let size = rule.size(*triangles);
                let tris = random_cube(*triangles, size, 1);
                // The generator can produce a zero-area triangle in f32; the field drops those, so
                // the benchmark does too, keeping every contestant's ids the field's.
                let tris: Vec<Tri> = tris.into_iter().filter(|t| !vlf_geom::is_degenerate(t[0], t[1], t[2])).collect();
                Ok(LoadedScene {
                    name: format!("random-{}-{}", short_count(*triangles), rule.tag()),
                    description: format!(
                        "{} random triangles in [-1, 1]³, half-extent {size:.4} ({} size), seed 1",
                        tris.len(),
                        rule.tag()
                    ),
                    triangles: tris,
                })
            }
            SceneSpec::Mesh { path } => {
                let scene =
                    vlf_bake::import::import_paths(&[path]).with_context(|| format!("importing {}", path.display()))?;
                let name = path.file_stem().map_or("mesh".into(), |s| s.to_string_lossy().into_owned());
                let tris = scene.vertices();
                Ok(LoadedScene {
                    description: format!("{} triangles from {}", tris.len(), file_label(path)),
                    name,
                    triangles: tris,
                })
            }
        }
    }
}

/// A path as the report shows it: relative to the workspace root when under it.
fn file_label(path: &Path) -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    match (path.canonicalize(), root.canonicalize()) {
        (Ok(p), Ok(r)) => p.strip_prefix(&r).map_or_else(|_| p.display().to_string(), |q| q.display().to_string()),
        _ => path.display().to_string(),
    }
}

/// The axis-aligned box of the triangles, in f64.
pub fn bounds(tris: &[Tri]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for v in tris.iter().flatten() {
        for k in 0..3 {
            lo[k] = lo[k].min(v[k] as f64);
            hi[k] = hi[k].max(v[k] as f64);
        }
    }
    (lo, hi)
}
