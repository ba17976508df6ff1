//! The integration tests of this package, in one test binary (one link instead of one per
//! file; see README, "Running the tests"). Each module is one former `tests/<name>.rs`.

mod approx_eval;
mod cleaning;
mod eval;
mod handles;
mod mixed;
mod synth;
mod transform;

/// A TOSCA null shape of the corpus (`cat0`, `david0`, …) as the generator's base shape.
fn tosca_base(name: &str) -> shrec_bench::synth::BaseShape {
    let file = wfem_corpus::mesh_path(&format!("tosca-bcicp-5k/TOSCA_Isometric/{name}.off")).unwrap();
    let (mesh, _) = mesh_fem::io::load(&file, &Default::default()).unwrap();
    shrec_bench::synth::BaseShape::new(name, mesh).unwrap()
}
