//! # shrec-bench
//!
//! The synthetic SHREC'10-style robustness benchmark of wfem (paper, Sect. 5, Tables 3–5):
//!
//! * [`transform`]: mesh surgery with vertex bookkeeping (edge-graph geodesics, sub-meshes,
//!   welding, QEM half-edge collapse), every result carrying its ground-truth map;
//! * [`synth`]: the nine SHREC'10 transformation classes (plus real TOSCA poses) at five
//!   strengths, written with ground truth and a manifest (`cargo xtask shrec`, docs/SHREC.md);
//! * [`eval`]: the feature and dense-descriptor tables (repeatability, robustness; Tables 3–4);
//! * [`protocol`]: the retrieval protocols — SHREC'10's cumulative "strength ≤ s" mAP beside the
//!   paper's Table 5, queries against a clean collection, and TOSCA-76 leave-one-out
//!   (`cargo xtask shrec-eval`, `cargo xtask tosca-eval`, docs/SHREC-RESULTS.md);
//! * [`approx_eval`]: the feature-driven approximation f = f_glob + f_loc (Sect. 4.2,
//!   Fig. 12–13) on real meshes, smooth and noisy (`cargo xtask approx-eval`,
//!   docs/APPROX-RESULTS.md);
//! * [`creatures`]: procedural bodies with limbs, training shapes outside every evaluation set
//!   (`cargo xtask creatures`, `cargo xtask real-eval --creatures N`);
//! * [`mixed`]: a generated mixed collection of 20 classes of corpus objects, rigid and not,
//!   each in stretched, bulged and remeshed variants (`cargo xtask real-eval --collections
//!   generated-mixed`).
//!
//! `xtask` is a thin command line over this crate. All randomness comes from the one seeded
//! generator [`wfem_base::rng::SplitMix64`].

#![warn(missing_docs)]
#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]

pub mod approx_eval;
pub mod creatures;
mod error;
pub mod eval;
pub mod handles;
pub mod mixed;
pub mod protocol;
pub mod real;
pub mod synth;
pub mod transform;

pub use error::BenchError;

/// FNV-1a, 64 bit: the one hash of the crate (random-stream seeds, eigenbasis cache keys).
/// Feed bytes with [`Fnv1a::eat`]; the value is `.0`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Fnv1a(pub(crate) u64);

impl Fnv1a {
    pub(crate) fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }

    pub(crate) fn eat(&mut self, bytes: impl IntoIterator<Item = u8>) {
        for b in bytes {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x0000_0100_0000_01B3);
        }
    }
}
