//! Arbitrary bytes → the medit volume reader → tetrahedra invariants or a typed error (see `wfem_fuzz`).
#![no_main]

use libfuzzer_sys::fuzz_target;
use mesh_fem::io::volume::VolumeFormat;

fuzz_target!(|data: &[u8]| {
    wfem_fuzz::read_volume_and_check(data, VolumeFormat::Medit);
});
