//! Arbitrary bytes → the obj reader → mesh invariants or a typed error (see `wfem_fuzz`).
#![no_main]

use libfuzzer_sys::fuzz_target;
use mesh_fem::io::MeshFormat;

fuzz_target!(|data: &[u8]| {
    wfem_fuzz::read_and_check(data, MeshFormat::Obj);
});
