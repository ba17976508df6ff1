//! What an index describes: a triangle mesh or a point cloud ([`ShapeRef`], [`AsShape`]).
//!
//! Both give the same [`ShapeDescriptors`](crate::descriptor::ShapeDescriptors) — L, B, D and their
//! eigenpairs — so everything after [`super::DescriptorSettings::shape`] (descriptors,
//! vocabularies, bags, distances) is one pipeline, and one collection may mix meshes and
//! clouds. A mesh is assembled with the Laplacian of the settings
//! ([`super::DescriptorSettings::laplacian`]), a cloud always with the robust construction
//! ([`mesh_fem::cloud::assemble_cloud`]).

use mesh_fem::cloud::PointCloud;
use mesh_fem::TriMesh;

/// A shape to describe, borrowed: a triangle mesh or a point cloud.
#[derive(Clone, Copy, Debug)]
pub enum ShapeRef<'a> {
    /// A triangle mesh.
    Mesh(&'a TriMesh),
    /// A point cloud (positions, optional normals; no faces).
    Cloud(&'a PointCloud),
}

impl ShapeRef<'_> {
    /// Its number of vertices (points for a cloud).
    pub fn n_vertices(&self) -> usize {
        match self {
            ShapeRef::Mesh(m) => m.n_vertices(),
            ShapeRef::Cloud(c) => c.n_points(),
        }
    }

    /// Whether it is a point cloud.
    pub fn is_cloud(&self) -> bool {
        matches!(self, ShapeRef::Cloud(_))
    }
}

/// Anything the retrieval model can describe: a [`TriMesh`], a [`PointCloud`], a file's
/// content ([`mesh_fem::io::Shape`], as [`mesh_fem::io::load_shape`] reads it) or a
/// [`ShapeRef`]. The entry points that take shapes (`ShapeFeatures::compute`,
/// `RetrievalIndex::build`, `RetrievalIndex::describe`, …) are generic over it and hand the
/// [`ShapeRef`] to one implementation.
pub trait AsShape: Sync {
    /// The shape, borrowed.
    fn as_shape(&self) -> ShapeRef<'_>;
}

impl AsShape for TriMesh {
    fn as_shape(&self) -> ShapeRef<'_> {
        ShapeRef::Mesh(self)
    }
}

impl AsShape for PointCloud {
    fn as_shape(&self) -> ShapeRef<'_> {
        ShapeRef::Cloud(self)
    }
}

impl AsShape for mesh_fem::io::Shape {
    fn as_shape(&self) -> ShapeRef<'_> {
        match self {
            mesh_fem::io::Shape::Mesh(mesh, _) => ShapeRef::Mesh(mesh),
            mesh_fem::io::Shape::Cloud(cloud) => ShapeRef::Cloud(cloud),
        }
    }
}

impl AsShape for ShapeRef<'_> {
    fn as_shape(&self) -> ShapeRef<'_> {
        *self
    }
}

impl<'a> From<&'a TriMesh> for ShapeRef<'a> {
    fn from(mesh: &'a TriMesh) -> Self {
        ShapeRef::Mesh(mesh)
    }
}

impl<'a> From<&'a PointCloud> for ShapeRef<'a> {
    fn from(cloud: &'a PointCloud) -> Self {
        ShapeRef::Cloud(cloud)
    }
}
