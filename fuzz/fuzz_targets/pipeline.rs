//! First byte chooses the format (and polygon triangulation), the rest is the file:
//! load → validate → assemble → operator invariants (see `wfem_fuzz::pipeline`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    wfem_fuzz::pipeline(data);
});
