//! Library side of the wfem project chores (`cargo xtask …`), so that the generators can be
//! tested.

#![warn(missing_docs)]

pub mod approx;
pub mod bench;
pub mod fusion_lab;
pub mod lab;
pub mod peers;
pub mod real_eval;
pub mod test_all;
pub mod wheel;
