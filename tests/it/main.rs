//! The integration tests of this package, in one test binary (one link instead of one per
//! file; see README, "Running the tests"). Each module is one former `tests/<name>.rs`.

mod architecture;
mod bad_input;
mod cli;
mod cli_approx;
mod cli_atomic;
mod cli_clouds;
mod cli_distance;
mod cli_first_hour;
mod cli_hks;
mod cli_index_safety;
mod cli_issue16;
mod cli_retrieval_eval;
mod cli_signals;
mod cli_volumes;
mod common;
mod crate_roots;
mod defaults;
mod doc_paths;
mod fuzz_regressions;
mod hostile;
mod module_cycles;
mod no_unwrap;
mod registry;
mod size_budget;
mod thin_library;
