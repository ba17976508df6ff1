//! Integration tests of wfem-base.

mod rng;
