//! # mesh-repair
//!
//! Repairs of triangle meshes that shape analysis needs before a Laplacian means what it should
//! (beyond the paper): every function takes a [`mesh_fem::TriMesh`] and its bounds explicitly and
//! returns a new mesh with a report of what it changed; the input is never modified.
//!
//! * [`holes`]: boundary loops and hole filling (smooth patches of new vertices, appended after
//!   the old ones, which stay as they were).
//! * [`handles`]: thin handles (short non-separating cycles) found and cut, pinched vertices
//!   unwelded into one copy per sheet.
//! * [`filter`]: isolated spikes put back ([`filter::despike`]); the edge-scale roughness and the
//!   height coherence that tell noise from shape.
//!
//! The bounds that retrieval uses (tuned on TOSCA and SHREC) are shape-retrieval's cleaning
//! policy (`shape_retrieval::model::DEFAULT_MAX_HOLE_PERIMETER` and the like), not defaults here.
//! The graph algorithms these repairs use (edge graph, Dijkstra, union-find) are mesh-fem's
//! [`mesh_fem::graph`].

#![warn(missing_docs)]
#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]

pub mod filter;
pub mod handles;
pub mod holes;

/// The README's example, compiled as a doc test.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
