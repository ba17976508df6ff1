//! # mesh-fem
//!
//! Triangle meshes in, linear finite-element operators out.
//!
//! * [`TriMesh`]: vertex positions and triangles, the one mesh type of wfem.
//! * [`io`]: reading OBJ, PLY, OFF and STL files and writing fields (PLY/NPY/CSV), atomically.
//! * [`validate`](mod@validate): a [`validate::ValidationReport`] naming every problem, and explicit repairs.
//! * [`vec3`]: the 3-vector helpers and bounding box every crate uses.
//! * [`stats`](mod@stats): counts, topology (Euler characteristic, genus, boundary loops) and geometry.
//! * [`mtx`]: Matrix Market reading and writing (atomic, shortest round-trip decimals) and, with
//!   the feature `nalgebra`, `nalgebra-sparse` conversions.
//! * [`topology`] and [`graph`]: the connectivity of a mesh (edges, fans, boundary loops,
//!   components, orientation), its vertex adjacency, edge graph with shortest paths, and
//!   disjoint sets — public, so that the repairs of `mesh-repair` and the benchmark reuse them.
//! * [`gradient`]: per-element gradients of the hat functions and the integrated divergence
//!   (`Gᵀ diag|T| G = L`), on meshes and intrinsic triangulations.
//! * [`refine`]: every triangle split into four at its edge midpoints (same surface, finer FEM).
//! * [`generate`]: icospheres, UV spheres, open grids, tori and an irregular "bumpy" sphere.
//! * [`assemble`] with [`AssemblyParams`]: [`FemOperators`], the cotangent stiffness L, the
//!   consistent mass B and the lumped mass D of the paper's Eq. (3) and Eq. (7) ([`Mass`],
//!   [`Lumping`]), assembled in parallel into faer sparse matrices.
//! * [`Laplacian`]: the registry of Laplacians (`cotan`, the default, or `robust` with
//!   [`RobustParams`]); [`intrinsic`]: the robust one, the intrinsic Delaunay Laplacian of the tufted
//!   cover (Sharp & Crane 2020) with B and D on the intrinsic triangulation.
//! * [`volume`]: tetrahedral meshes ([`volume::TetMesh`]): validation, repairs, the boundary
//!   surface and the same L, B, D on tetrahedra ([`volume::assemble_volume`]); readers in
//!   [`io::volume`] (MEDIT, Gmsh 2.2/4.1, VTK legacy, TetGen).
//! * [`cloud`]: point clouds ([`PointCloud`](cloud::PointCloud)) and their robust L, B, D from local
//!   triangulations of the k nearest neighbours ([`assemble_cloud`](cloud::assemble_cloud)).
//!
//! **Sign convention.** Throughout wfem the stiffness matrix L is symmetric positive
//! semidefinite: positive diagonal, non-positive off-diagonal entries on well-shaped meshes,
//! `L·1 = 0`. The paper prints Eq. (3) with the opposite sign (libigl's `cotmatrix` also uses
//! the opposite sign).

#![warn(missing_docs)]
// Robustness (issue #8): no unwrap()/expect() on user-controlled data in library code; the few
// justified ones carry `#[allow]` and an `// invariant:` comment (checked by tests/no_unwrap.rs).
#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]

mod assembly;
mod error;
mod laplacian;
mod mesh;
mod operators;

pub mod cloud;
pub mod generate;
pub mod gradient;
pub mod graph;
pub mod intrinsic;
pub mod io;
pub mod morse;
pub mod mtx;
pub mod refine;
pub mod stats;
pub mod topology;
pub mod validate;
pub mod vec3;
pub mod volume;

// The curated root (ARCHITECTURE.md, "Crate roots"): the mesh, the operators and how they are
// assembled, the error. Every other item is reached through its public module only.
pub use assembly::assemble;
pub use error::{MeshError, Remedy};
pub use laplacian::{Laplacian, RobustParams};
pub use mesh::TriMesh;
pub use operators::{AssemblyParams, FemOperators, Lumping, Mass};
