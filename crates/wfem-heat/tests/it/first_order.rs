//! Taylor (paper, Eq. (9)) and backward-Euler steps against the dense reference: both are
//! first-order methods whose one-step (local) error is O(t²), so halving t divides the
//! error by ≈4 once tλ is small on the spectral support of f.
use crate::common;
use common::*;
use mesh_fem::{generate, Mass};
use wfem_heat::method::Method;
use wfem_heat::{HeatKernel, HeatParams};

#[test]
fn taylor_and_backward_euler_local_error_is_second_order() {
    let (mesh, ops) = ops_of(&generate::icosphere(3));
    // A smooth function (spherical-harmonic degrees ≤ 2) so that tλ ≪ 1 on its support.
    let f: Vec<f64> = mesh.positions().iter().map(|p| p[0] + p[1] * p[2]).collect();
    for kind in [Mass::Consistent, Mass::Lumped(Default::default())] {
        let dense = HeatKernel::new(
            &ops,
            HeatParams {
                mass: kind,
                method: Method::Dense,
            },
        )
        .unwrap();
        for method in [Method::Taylor, Method::BackwardEuler] {
            let k = HeatKernel::new(
                &ops,
                HeatParams {
                    mass: kind,
                    method: method.clone(),
                },
            )
            .unwrap();
            let errs: Vec<f64> = [2e-4, 1e-4, 5e-5]
                .iter()
                .map(|&t| {
                    let g = k.apply(&f, t).unwrap();
                    let r = dense.apply(&f, t).unwrap();
                    rel_err(&g, &r)
                })
                .collect();
            for w in errs.windows(2) {
                let ratio = w[0] / w[1];
                assert!((3.3..4.7).contains(&ratio), "{kind:?} {method:?}: errors {errs:?}");
            }
            // And it really is an approximation, not the exact kernel.
            assert!(errs[2] > 1e-10, "{kind:?} {method:?}: {errs:?}");
        }
    }
}
