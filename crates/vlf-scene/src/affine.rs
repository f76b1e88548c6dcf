//! Affine transforms: rotation, non-uniform scale, mirroring, shear and translation, as a 3×4
//! matrix in f64, and the boxes and rays they move.

// `!(a <= b)` is meant: it is true when either side is NaN, which must fail the test.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

/// An affine map `p ↦ A p + b` of 3-space: the first three rows of a row-major 4×4 matrix whose
/// last row is `0 0 0 1`. Always invertible: the constructors refuse singular matrices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Affine {
    /// Rows of `[A | b]`.
    m: [[f64; 4]; 3],
}

/// Why a matrix is not an affine transform this crate accepts.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum AffineError {
    /// A coefficient is NaN or infinite.
    #[error("coefficient {index} (row {row}, column {column}) is not a finite number", row = .index / 4, column = .index % 4)]
    NotFinite {
        /// The coefficient's index in the row-major 4×4 matrix.
        index: usize,
    },
    /// The last row of a 4×4 matrix is not `0 0 0 1`: a projective map, not an affine one.
    #[error("its last row is {0:?}, not [0, 0, 0, 1]: an affine transform's last row is 0 0 0 1")]
    NotAffine([f64; 4]),
    /// The linear part cannot be inverted (or so nearly not that rays would lose all precision).
    #[error(
        "it is singular: the determinant of its 3×3 part is {determinant:e}, against {scale:e} for its columns' lengths (it flattens space)"
    )]
    Singular {
        /// `det A`.
        determinant: f64,
        /// The product of `A`'s column lengths, what the determinant is compared to.
        scale: f64,
    },
    /// The linear part scales space by more (or less) than double precision can follow: a
    /// column's length, their product or the determinant overflows, or the product underflows to
    /// zero from lengths that are not zero.
    #[error(
        "its scale is out of range: column {column} of its 3×3 part is {length:e} long and its determinant is {determinant:e}, beyond what double precision can follow; scale the mesh itself instead"
    )]
    OutOfRange {
        /// The longest column (the shortest, if the product underflows).
        column: usize,
        /// That column's length.
        length: f64,
        /// `det A` as computed.
        determinant: f64,
    },
}

/// The smallest `|det A| / (|a₁| |a₂| |a₃|)` (the volume of the image of a unit cube relative to
/// that of its edges' images) accepted: below it the inverse amplifies rounding by more than
/// about 10⁹, and rays transformed into the instance would be meaningless.
const MIN_CONDITION: f64 = 1e-9;

impl Affine {
    /// The identity.
    pub const IDENTITY: Affine = Affine { m: [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]] };

    /// A translation by `t`.
    pub fn translation(t: [f64; 3]) -> Affine {
        let mut a = Affine::IDENTITY;
        for (i, row) in a.m.iter_mut().enumerate() {
            row[3] = t[i];
        }
        a
    }

    /// The rotation by `radians` about the line through `centre` along `axis` (right-handed:
    /// counter-clockwise seen from the tip of `axis`). `None` if `axis` is zero or a value is
    /// not finite.
    pub fn rotation_about(axis: [f64; 3], radians: f64, centre: [f64; 3]) -> Option<Affine> {
        let len = axis.iter().map(|a| a * a).sum::<f64>().sqrt();
        if !(len > 0.0 && len.is_finite() && radians.is_finite() && centre.iter().all(|c| c.is_finite())) {
            return None;
        }
        let [x, y, z] = axis.map(|a| a / len);
        let (s, c) = radians.sin_cos();
        let t = 1.0 - c;
        let r = [
            [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
            [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
        ];
        // p ↦ R (p − centre) + centre.
        let m = std::array::from_fn(|i| {
            let b = centre[i] - (0..3).map(|k| r[i][k] * centre[k]).sum::<f64>();
            [r[i][0], r[i][1], r[i][2], b]
        });
        Affine::from_3x4(m).ok()
    }

    /// From the 16 numbers of a row-major 4×4 matrix (the scene file's `"transform"`), whose last
    /// row must be `0 0 0 1`.
    ///
    /// # Errors
    /// A coefficient that is not finite, a last row other than `0 0 0 1`, a singular matrix.
    pub fn from_rows(m: &[f64; 16]) -> Result<Affine, AffineError> {
        if let Some(index) = m.iter().position(|v| !v.is_finite()) {
            return Err(AffineError::NotFinite { index });
        }
        let last = [m[12], m[13], m[14], m[15]];
        if last != [0.0, 0.0, 0.0, 1.0] {
            return Err(AffineError::NotAffine(last));
        }
        Affine::from_3x4(std::array::from_fn(|r| std::array::from_fn(|c| m[4 * r + c])))
    }

    /// From the rows of `[A | b]`.
    ///
    /// # Errors
    /// A coefficient that is not finite, or a singular `A`.
    pub fn from_3x4(m: [[f64; 4]; 3]) -> Result<Affine, AffineError> {
        if let Some(index) = m.iter().flatten().position(|v| !v.is_finite()) {
            return Err(AffineError::NotFinite { index });
        }
        let a = Affine { m };
        let determinant = a.determinant();
        // Each column's length, scaled by its largest entry so that it overflows only past f64.
        let length = |c: usize| {
            let big = (0..3).map(|r| m[r][c].abs()).fold(0.0, f64::max);
            if big == 0.0 { 0.0 } else { big * (0..3).map(|r| (m[r][c] / big).powi(2)).sum::<f64>().sqrt() }
        };
        let lengths = [length(0), length(1), length(2)];
        let scale = lengths[0] * lengths[1] * lengths[2];
        // Out of range, not singular: a length, their product or the determinant overflows, or
        // the product of lengths that are not zero underflows to zero.
        let longest = (0..3).fold(0, |best, c| if lengths[c] > lengths[best] { c } else { best });
        let shortest = (0..3).fold(0, |best, c| if lengths[c] < lengths[best] { c } else { best });
        let out_of_range = if !lengths[longest].is_finite() || !scale.is_finite() || !determinant.is_finite() {
            Some(longest)
        } else if scale == 0.0 && lengths[shortest] > 0.0 {
            Some(shortest)
        } else {
            None
        };
        if let Some(column) = out_of_range {
            return Err(AffineError::OutOfRange { column, length: lengths[column], determinant });
        }
        if !(determinant.abs() > MIN_CONDITION * scale) {
            return Err(AffineError::Singular { determinant, scale });
        }
        Ok(a)
    }

    /// The rows of `[A | b]`.
    pub fn rows(&self) -> [[f64; 4]; 3] {
        self.m
    }

    /// The 16 numbers of the row-major 4×4 matrix.
    pub fn to_rows(&self) -> [f64; 16] {
        let mut out = [0.0; 16];
        for r in 0..3 {
            out[4 * r..4 * r + 4].copy_from_slice(&self.m[r]);
        }
        out[15] = 1.0;
        out
    }

    /// `det A`: negative for a mirroring transform.
    pub fn determinant(&self) -> f64 {
        let m = &self.m;
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    }

    /// `A p + b`.
    #[inline]
    pub fn point(&self, p: [f64; 3]) -> [f64; 3] {
        let m = &self.m;
        std::array::from_fn(|r| m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2] + m[r][3])
    }

    /// `A v`.
    #[inline]
    pub fn vector(&self, v: [f64; 3]) -> [f64; 3] {
        let m = &self.m;
        std::array::from_fn(|r| m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2])
    }

    /// The inverse map (which exists: the constructors refuse singular matrices).
    pub fn inverse(&self) -> Affine {
        let m = &self.m;
        let det = self.determinant();
        let inv = 1.0 / det;
        // The adjugate of A, over the determinant.
        let a = [
            [
                (m[1][1] * m[2][2] - m[1][2] * m[2][1]) * inv,
                (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * inv,
                (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * inv,
            ],
            [
                (m[1][2] * m[2][0] - m[1][0] * m[2][2]) * inv,
                (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * inv,
                (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * inv,
            ],
            [
                (m[1][0] * m[2][1] - m[1][1] * m[2][0]) * inv,
                (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * inv,
                (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * inv,
            ],
        ];
        let b = [m[0][3], m[1][3], m[2][3]];
        let t: [f64; 3] = std::array::from_fn(|r| -(a[r][0] * b[0] + a[r][1] * b[1] + a[r][2] * b[2]));
        Affine { m: std::array::from_fn(|r| [a[r][0], a[r][1], a[r][2], t[r]]) }
    }

    /// `self ∘ other`: first `other`, then `self`. `None` if the product is singular or not
    /// finite (two valid transforms can underflow or overflow together).
    pub fn then_after(&self, other: &Affine) -> Option<Affine> {
        let (a, b) = (&self.m, &other.m);
        let m: [[f64; 4]; 3] = std::array::from_fn(|r| {
            std::array::from_fn(|c| {
                let lin = a[r][0] * b[0][c] + a[r][1] * b[1][c] + a[r][2] * b[2][c];
                if c == 3 { lin + a[r][3] } else { lin }
            })
        });
        Affine::from_3x4(m).ok()
    }

    /// The box around the image of the box `[lo, hi]` (its eight corners mapped).
    pub fn bounds(&self, lo: [f64; 3], hi: [f64; 3]) -> ([f64; 3], [f64; 3]) {
        let mut out = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for corner in 0..8 {
            let p = [0, 1, 2].map(|k| if corner >> k & 1 == 0 { lo[k] } else { hi[k] });
            let q = self.point(p);
            for (k, &v) in q.iter().enumerate() {
                out.0[k] = out.0[k].min(v);
                out.1[k] = out.1[k].max(v);
            }
        }
        out
    }
}

impl Default for Affine {
    fn default() -> Self {
        Affine::IDENTITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f64; 3], b: [f64; 3]) -> bool {
        (0..3).all(|k| (a[k] - b[k]).abs() <= 1e-12 * (1.0 + a[k].abs()))
    }

    #[test]
    fn the_inverse_undoes_a_mirroring_non_uniform_transform() {
        let a =
            Affine::from_rows(&[0.0, -2.0, 0.0, 1.0, 3.0, 0.0, 0.5, -4.0, 0.0, 0.0, -0.25, 7.0, 0.0, 0.0, 0.0, 1.0])
                .unwrap();
        assert!(a.determinant() < 0.0, "mirrored");
        let inv = a.inverse();
        for p in [[0.0, 0.0, 0.0], [1.0, -2.0, 3.5], [1e3, 1e-3, -7.0]] {
            assert!(close(inv.point(a.point(p)), p));
            assert!(close(a.vector(inv.vector(p)), p));
        }
        let both = a.then_after(&inv).unwrap();
        assert!(close(both.point([5.0, 6.0, 7.0]), [5.0, 6.0, 7.0]));
    }

    #[test]
    fn bad_matrices_are_refused_by_name() {
        let mut m = Affine::IDENTITY.to_rows();
        m[5] = f64::NAN;
        assert_eq!(Affine::from_rows(&m), Err(AffineError::NotFinite { index: 5 }));
        let mut m = Affine::IDENTITY.to_rows();
        m[14] = 1.0;
        assert!(matches!(Affine::from_rows(&m), Err(AffineError::NotAffine(_))));
        let mut m = Affine::IDENTITY.to_rows();
        m[10] = 0.0;
        assert!(matches!(Affine::from_rows(&m), Err(AffineError::Singular { .. })));
        // Two columns nearly parallel: singular in all but name.
        let m = [1.0, 1.0, 0.0, 0.0, 0.0, 1e-12, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0];
        assert!(matches!(Affine::from_rows(&m), Err(AffineError::Singular { .. })));
        let msg = Affine::from_rows(&[0.0; 16]).unwrap_err().to_string();
        assert!(msg.contains("last row"), "{msg}");
        // Scales double precision cannot follow are out of range, not singular: a column whose
        // length overflows, one that underflows to zero, a determinant that overflows.
        let scaled =
            |x: f64, y: f64, z: f64| [x, 0.0, 0.0, 0.0, 0.0, y, 0.0, 0.0, 0.0, 0.0, z, 0.0, 0.0, 0.0, 0.0, 1.0];
        let e = Affine::from_rows(&scaled(1e300, 1e300, 1e300)).unwrap_err();
        assert_eq!(e, AffineError::OutOfRange { column: 0, length: 1e300, determinant: f64::INFINITY });
        assert!(e.to_string().starts_with("its scale is out of range: column 0 of its 3×3 part is 1e300 long"), "{e}");
        let e = Affine::from_rows(&scaled(1.0, 1e-170, 1e-170)).unwrap_err();
        assert_eq!(e, AffineError::OutOfRange { column: 1, length: 1e-170, determinant: 0.0 });
        assert!(Affine::from_rows(&scaled(1.0, 1e-150, 1.0)).is_ok(), "small, yet invertible");
        assert!(Affine::from_rows(&scaled(1.0, 1.0, 1e200)).is_ok());
        assert!(matches!(Affine::from_rows(&scaled(1e200, 1e200, 1.0)), Err(AffineError::OutOfRange { .. })));
        assert!(Affine::from_rows(&scaled(f64::MAX, 1.0, 1.0)).is_ok(), "f64::MAX itself is a length");
        let mut m = scaled(1.0, 1.0, 1.0);
        m[4] = f64::MAX;
        m[8] = f64::MAX;
        assert!(matches!(Affine::from_rows(&m), Err(AffineError::OutOfRange { column: 0, .. })), "a column past f64");
    }

    #[test]
    fn a_quarter_turn_about_a_line_moves_points_around_it() {
        let r = Affine::rotation_about([0.0, 0.0, 2.0], std::f64::consts::FRAC_PI_2, [1.0, 1.0, 0.0]).unwrap();
        assert!(close(r.point([2.0, 1.0, 5.0]), [1.0, 2.0, 5.0]));
        assert!(close(r.point([1.0, 1.0, -3.0]), [1.0, 1.0, -3.0]));
        assert!((r.determinant() - 1.0).abs() < 1e-12);
        assert!(Affine::rotation_about([0.0; 3], 1.0, [0.0; 3]).is_none());
    }

    #[test]
    fn bounds_hold_every_mapped_corner() {
        let a = Affine::from_3x4([[0.6, -0.8, 0.0, 1.0], [0.8, 0.6, 0.0, 2.0], [0.0, 0.0, -3.0, 0.0]]).unwrap();
        let (lo, hi) = a.bounds([-1.0, -1.0, 0.0], [1.0, 2.0, 1.0]);
        for p in [[-1.0, -1.0, 0.0], [1.0, 2.0, 1.0], [1.0, -1.0, 0.5]] {
            let q = a.point(p);
            assert!((0..3).all(|k| lo[k] <= q[k] && q[k] <= hi[k]));
        }
        assert_eq!((lo[2], hi[2]), (-3.0, 0.0));
    }
}
