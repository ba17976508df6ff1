//! The integration tests of this package, in one test binary (one link instead of one per
//! file; see README, "Running the tests"). Each module is one former `tests/<name>.rs`.

mod common;

mod algebra;
mod approx;
mod basis;
mod clouds;
mod diagonal;
mod distance;
mod edge_cases;
mod eigen_scale;
mod errors;
mod failure_paths;
mod fast_path;
mod first_order;
mod geodesic;
mod properties;
mod rational;
mod scale;
mod spectral;
mod times;
mod volumes;
