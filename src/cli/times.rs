//! Diffusion times on the command line: the unit they are read in (`--time-unit`, the
//! library's [`TimeUnit`] registry), their record in the sidecars, and the warning for a
//! time whose result carries no information (wfem_heat's [`TimeScales`]).

use super::choice::choice;
use super::{progress, CliError};
use clap::Args;
use mesh_fem::TriMesh;
use serde_json::json;
use shape_retrieval::sihks::{MeshLengths, TimeUnit};
use wfem_base::Choice;
use wfem_heat::times::TimeScales;
use wfem_heat::Operators;

/// `--time-unit`: the unit of every time argument of a command.
#[derive(Args, Clone, Copy, Debug, Default)]
pub struct TimeUnitArgs {
    /// The unit of the times given: t = τ·unit.
    #[arg(long, value_parser = choice::<TimeUnit>(), default_value = TimeUnit::default_name())]
    pub time_unit: TimeUnit,
}

/// Times as given and in the mesh's units.
#[derive(Clone, Debug)]
pub struct Times {
    /// The flag they came from (for messages).
    pub flag: &'static str,
    /// The values as given (τ).
    pub given: Vec<f64>,
    /// `t = τ·unit`, in the mesh's squared length units.
    pub absolute: Vec<f64>,
    /// The unit.
    pub unit: TimeUnit,
    /// Its value on this mesh (1, A or ℓ̄²).
    pub unit_value: f64,
}

impl TimeUnitArgs {
    /// Reads the times `given` in the chosen unit on `mesh`.
    ///
    /// # Errors
    /// [`CliError::OutOfRange`] if a time in the mesh's units is not a finite positive number
    /// (a huge τ times a huge area).
    pub fn resolve(&self, flag: &'static str, mesh: &TriMesh, given: &[f64]) -> Result<Times, CliError> {
        let unit = self.time_unit.with_factor(1.0);
        let lengths = match unit {
            // The edge lengths need the edges (O(F log F)); the other units do not.
            TimeUnit::Edge(_) => MeshLengths::of(mesh),
            _ => MeshLengths {
                area: mesh.area(),
                mean_edge_length: 0.0,
            },
        };
        let unit_value = unit
            .on(&lengths)
            .map_err(|e| CliError::Usage(format!("--time-unit {}: {e}", unit.name())))?;
        let absolute: Vec<f64> = given.iter().map(|t| t * unit_value).collect();
        for (&t, &g) in absolute.iter().zip(given) {
            if g.is_finite() && g > 0.0 && !t.is_finite() {
                // The given time is fine; its product with the unit is not (issue #41).
                return Err(CliError::Usage(format!(
                    "{flag} {g:e} --time-unit {}: {g:e} × {unit_value:.4e} (the unit on this mesh) overflows; give a smaller time",
                    unit.name()
                )));
            }
            super::limits::time(flag, t)?;
        }
        Ok(Times {
            flag,
            given: given.to_vec(),
            absolute,
            unit: self.time_unit,
            unit_value,
        })
    }
}

impl Times {
    /// The unit's suffix in (ASCII) figure titles: `""`, `"*A"` or `"*edge^2"`.
    pub fn suffix(&self) -> &'static str {
        match self.unit {
            TimeUnit::Absolute(_) => "",
            TimeUnit::Area(_) => "*A",
            TimeUnit::Edge(_) => "*edge^2",
        }
    }

    /// The sidecar entry: the unit's name and value, and the times as given.
    pub fn meta(&self) -> serde_json::Value {
        json!({ "name": self.unit.name(), "value": self.unit_value, "given": self.given })
    }

    /// Warns (once per kind) about the times whose result carries no information: so small
    /// that the result equals the input, or past the time at infinity; the message names the
    /// sensible range in the unit the times were given in. `doubling` is 2 for a result made
    /// of kernel values at 2t (the diffusion distance, Eq. (18): `d_t² = k_{2t}(i,i) +
    /// k_{2t}(j,j) − 2k_{2t}(i,j)`), else 1.
    ///
    /// # Errors
    /// A failure of the eigenvalue λ₂ (computed only for a time near the time at infinity).
    pub fn warn(&self, ops: &Operators, mesh: &TriMesh, doubling: f64) -> Result<(), CliError> {
        let scales = TimeScales::new(ops, Some(mesh.positions()))?;
        let mut said = [false; 2];
        for &t in &self.absolute {
            if let Some(w) = scales.check(doubling * t)?.map(|w| w.in_unit(doubling)) {
                let kind = matches!(w, wfem_heat::times::TimeWarning::PastInfinity { .. }) as usize;
                if !said[kind] {
                    said[kind] = true;
                    progress::warn(&warning_text(self.flag, &w.in_unit(self.unit_value), self.unit));
                }
            }
        }
        Ok(())
    }
}

/// The warning as the CLI prints it: the flag, the times in the user's unit.
fn warning_text(flag: &str, w: &wfem_heat::times::TimeWarning, unit: TimeUnit) -> String {
    let unit = match unit {
        TimeUnit::Absolute(_) => String::new(),
        u => format!(" (--time-unit {})", u.name()),
    };
    format!("{flag}: {w}{unit}")
}
