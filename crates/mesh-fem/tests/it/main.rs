//! The integration tests of this package, in one test binary (one link instead of one per
//! file; see README, "Running the tests"). Each module is one former `tests/<name>.rs`.

mod minimal_reader;

mod cloud;
mod corpus;
mod generate;
mod gradient;
mod io_obj_oracle;
mod io_points;
mod io_readers;
mod io_special_files;
mod io_writers;
mod morse;
mod mtx;
mod operators;
mod refine;
mod robust;
mod stats;
mod validate;
mod volume;
