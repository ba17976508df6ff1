//! [`assemble`]: the operators of a mesh with the chosen Laplacian. The one dispatch over
//! [`Laplacian`], above the modules that build each one ([`crate::operators`] the cotangent
//! operators, [`crate::intrinsic`] the robust ones), so that neither of them knows the other's
//! caller.

use crate::laplacian::Laplacian;
use crate::operators::{assemble_cotan, AssemblyParams, FemOperators};
use crate::{MeshError, TriMesh};

/// Assembles the stiffness L, the consistent mass B and the lumped mass D of `mesh`
/// (paper, Eq. (3) and Eq. (7)) with the Laplacian of `params.laplacian`: the cotangent
/// operators of the mesh itself (the default, [`FemOperators`](crate::FemOperators); an O(#faces)
/// parallel assembly), or the robust operators of [`crate::intrinsic::assemble_robust`]
/// (whose errors it returns instead of the ones below).
///
/// # Errors
/// * [`MeshError::DegenerateFace`] for a face of zero or numerically zero area (its
///   cotangents are undefined; the test is [`crate::validate::is_degenerate_triangle`]), the
///   first one in face order; drop such faces first with [`crate::validate::repair`].
/// * [`MeshError::UnreferencedVertex`] for a vertex that belongs to no face (B would be
///   singular); drop such vertices first with [`crate::validate::repair`].
/// * [`MeshError::DegenerateMesh`] if the total area Σ|T| overflows (coordinates beyond
///   ~1e154): B and D would hold infinities; scale the mesh down first.
/// * [`MeshError::Invalid`] for a mesh of 2³² faces or more.
pub fn assemble(mesh: &TriMesh, params: &AssemblyParams) -> Result<FemOperators, MeshError> {
    match params.laplacian {
        Laplacian::Cotan => assemble_cotan(mesh, params),
        Laplacian::Robust(robust) => crate::intrinsic::assemble_robust(mesh, &robust, params).map(|(ops, _)| ops),
    }
}
