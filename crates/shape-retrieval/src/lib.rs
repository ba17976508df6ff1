//! # shape-retrieval
//!
//! Heat kernel shape descriptors (HKS, scale-invariant HKS), feature points, bags of
//! features and retrieval metrics on top of [`wfem_heat`].

#![warn(missing_docs)]

mod error;
pub use error::RetrievalError;
