//! Library side of the wfem project chores (`cargo xtask …`), so that the generators can be
//! tested.

#![warn(missing_docs)]

pub mod bench;
pub mod eval;
pub mod peers;
pub mod shrec;
pub mod test_all;
