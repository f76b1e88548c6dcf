//! Node transforms: column-major 4×4 matrices in f64, composed down the node tree, and points
//! moved to world space.

use ::gltf as gl;

/// Column-major 4×4 matrix, `m[column][row]`, like glTF.
pub(super) type Mat4 = [[f64; 4]; 4];

pub(super) const IDENTITY: Mat4 =
    [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];

/// A node's local transform as a column-major f64 matrix; a TRS transform is composed in f64
/// (`T·R·S`, the quaternion used as given).
pub(super) fn local_matrix(transform: gl::scene::Transform) -> Mat4 {
    match transform {
        gl::scene::Transform::Matrix { matrix } => matrix.map(|column| column.map(f64::from)),
        gl::scene::Transform::Decomposed { translation, rotation, scale } => {
            let [x, y, z, w] = rotation.map(f64::from);
            let [sx, sy, sz] = scale.map(f64::from);
            let [tx, ty, tz] = translation.map(f64::from);
            // Rotation matrix, row-major r[row][column].
            let r = [
                [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)],
                [2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)],
                [2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)],
            ];
            let s = [sx, sy, sz];
            let mut m = IDENTITY;
            for (column, m_column) in m.iter_mut().take(3).enumerate() {
                for row in 0..3 {
                    m_column[row] = r[row][column] * s[column];
                }
            }
            m[3] = [tx, ty, tz, 1.0];
            m
        }
    }
}

/// `a · b` for column-major matrices.
pub(super) fn mul(a: &Mat4, b: &Mat4) -> Mat4 {
    std::array::from_fn(|column| std::array::from_fn(|row| (0..4).map(|k| a[k][row] * b[column][k]).sum()))
}

/// The affine image of `p` under `m`, in f64 (the scene keeps world coordinates in f64 until it
/// knows its centre). A point with a non-finite coordinate is returned as it is, so that the
/// error names the value in the file (a NaN would otherwise spread to every coordinate).
pub(super) fn transform_point(m: &Mat4, p: [f32; 3]) -> [f64; 3] {
    let [x, y, z] = p.map(f64::from);
    if !p.iter().all(|c| c.is_finite()) {
        return [x, y, z];
    }
    std::array::from_fn(|row| m[0][row] * x + m[1][row] * y + m[2][row] * z + m[3][row])
}

/// The part of a node's transform that is not finite, as (its glTF property, the element): a
/// number beyond the ±3.4e38 of f32 (`1e39`, say) is read as infinite, and would turn the node's
/// vertices into NaN, blamed on them instead of on the node.
pub(super) fn non_finite_part(transform: &gl::scene::Transform) -> Option<(&'static str, usize)> {
    let first = |v: &[f32]| v.iter().position(|c| !c.is_finite());
    match transform {
        gl::scene::Transform::Matrix { matrix } => first(matrix.as_flattened()).map(|k| ("matrix", k)),
        gl::scene::Transform::Decomposed { translation, rotation, scale } => {
            [("translation", &translation[..]), ("rotation", &rotation[..]), ("scale", &scale[..])]
                .into_iter()
                .find_map(|(name, v)| first(v).map(|k| (name, k)))
        }
    }
}
