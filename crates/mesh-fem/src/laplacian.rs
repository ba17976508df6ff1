//! Which Laplacian [`crate::assemble`] builds: the registry of stiffness matrices.
//!
//! Every Laplacian gives the same three operators ([`crate::FemOperators`]: the stiffness L,
//! symmetric positive semidefinite with a positive diagonal and `L·1 = 0`; the consistent
//! mass B; the lumped mass D), so the heat kernel, the distances and the descriptors consume
//! them unchanged. One module per Laplacian:
//!
//! | variant | module | triangulation the operators live on |
//! |---|---|---|
//! | [`Laplacian::Cotan`] (default) | [`crate::operators`] | the mesh itself (paper Eq. (3), (7); = libigl) |
//! | [`Laplacian::Robust`] | [`crate::intrinsic`] | the intrinsic Delaunay triangulation of the mesh's tufted cover (Sharp & Crane 2020; = robust_laplacian) |
//!
//! Point clouds ([`crate::cloud`]) always use the intrinsic construction.

use crate::MeshError;

/// The default relative mollification of the robust Laplacian, δ = 1e-5 × the mean edge
/// length (robust_laplacian's default).
pub(crate) const DEFAULT_MOLLIFY_FACTOR: f64 = 1e-5;

/// Parameters of the robust (intrinsic Delaunay, tufted cover) Laplacian.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RobustParams {
    /// Relative mollification: every edge length is increased by the smallest ε ≥ 0 that
    /// gives each triangle a margin of δ = `mollify_factor` × the mean edge length in its
    /// triangle inequalities (Sharp & Crane 2020, Sect. 4.5). 0 turns it off (a degenerate
    /// triangle is then refused). Must be finite and ≥ 0.
    pub mollify_factor: f64,
}

impl Default for RobustParams {
    fn default() -> Self {
        Self {
            mollify_factor: DEFAULT_MOLLIFY_FACTOR,
        }
    }
}

impl RobustParams {
    /// Checks the parameters.
    ///
    /// # Errors
    /// [`MeshError::InvalidParameter`] for a mollification factor that is negative or not
    /// finite.
    pub fn validate(&self) -> Result<(), MeshError> {
        if !(self.mollify_factor.is_finite() && self.mollify_factor >= 0.0) {
            return Err(MeshError::InvalidParameter {
                name: "mollify_factor",
                value: self.mollify_factor,
                expected: "a finite number ≥ 0",
            });
        }
        Ok(())
    }
}

/// Which stiffness matrix L (and which triangulation its masses B and D live on).
///
/// In every case L is symmetric positive semidefinite with a positive diagonal and `L·1 = 0`
/// (the opposite sign of libigl's `cotmatrix` and of the paper's Eq. (3)).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Laplacian {
    /// The cotangent Laplacian of the mesh itself, `L_ij = −½ (cot α_ij + cot β_ij)` (paper
    /// Eq. (3)), with B and D on the mesh's triangles. Equal to libigl's `cotmatrix` (with
    /// the opposite sign). Refuses degenerate faces; on non-manifold or badly shaped meshes
    /// its off-diagonal entries can be positive and heat can go negative.
    #[default]
    Cotan,
    /// The intrinsic Delaunay Laplacian of the tufted cover (Sharp & Crane, "A Laplacian for
    /// Nonmanifold Triangle Meshes", SGP 2020), with B and D on the intrinsic triangulation:
    /// an M-matrix (off-diagonals ≤ 0 up to a 1e-6 Delaunay tolerance) on any triangle soup —
    /// non-manifold edges and vertices, inconsistent orientation, (near-)degenerate faces.
    /// Equal to robust_laplacian's `mesh_laplacian` (L and the lumped mass); on a closed
    /// manifold mesh whose triangulation is already Delaunay it is the cotangent L.
    Robust(RobustParams),
}

wfem_base::registry! {
    Laplacian as "Laplacian" {
        Laplacian::Cotan = Laplacian::Cotan => "cotan" ["cotangent"]:
            "cotangent L of the mesh (paper Eq. (3), = libigl); the default",
        Laplacian::Robust(_) = Laplacian::Robust(RobustParams::default()) => "robust" ["intrinsic-delaunay", "tufted"]:
            "intrinsic Delaunay L of the tufted cover (Sharp & Crane 2020, = robust_laplacian): for point clouds and non-manifold, badly oriented or degenerate meshes",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        use wfem_base::Choice;
        wfem_base::check_registry::<Laplacian>().unwrap();
        assert_eq!(
            Laplacian::parse("robust").unwrap(),
            Laplacian::Robust(RobustParams::default())
        );
        assert_eq!(Laplacian::parse("Intrinsic_Delaunay").unwrap().name(), "robust");
        assert!(Laplacian::parse("intrinsic").is_err());
        assert_eq!(Laplacian::default(), Laplacian::Cotan);
    }

    #[test]
    fn mollify_factor_is_checked() {
        for bad in [-1e-5, f64::NAN, f64::INFINITY] {
            let err = RobustParams { mollify_factor: bad }.validate().unwrap_err();
            assert!(
                matches!(
                    err,
                    MeshError::InvalidParameter {
                        name: "mollify_factor",
                        ..
                    }
                ),
                "{err}"
            );
        }
        RobustParams { mollify_factor: 0.0 }.validate().unwrap();
    }
}
