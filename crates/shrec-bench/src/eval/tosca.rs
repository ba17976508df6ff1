//! TOSCA-76 leave-one-out with given settings (`cargo xtask tosca-eval`).

use crate::protocol::{self, leave_one_out, EigenCache, LooReport};
use crate::BenchError;
use shape_retrieval::model::RetrievalSettings;
use std::fmt::Write as _;
use std::path::Path;

/// TOSCA-76 leave-one-out with given settings (`cargo xtask tosca-eval`).
#[derive(Clone, Debug, PartialEq)]
pub struct ToscaEval {
    /// The settings evaluated.
    pub settings: RetrievalSettings,
    /// Number of outside training shapes.
    pub n_outside: usize,
    /// Vocabulary trained on the 76 with the settings' seed (what `wfem retrieval build` does).
    pub inside: LooReport,
    /// Vocabulary trained on the outside shapes with the settings' seed.
    pub outside: LooReport,
    /// mAP over the seeds `0 .. seeds` of k-means: (inside, outside) per seed.
    pub over_seeds: Vec<(u64, f64, f64)>,
}

/// Runs TOSCA-76 leave-one-out: each of the 76 shapes queries the other 75, relevant = same
/// class, with a vocabulary trained on the 76 (the CLI's `build` without `--vocab`) and with one
/// trained on [`protocol::outside_files`]; then the same for k-means seeds `0 .. seeds`.
///
/// # Errors
/// The first failure, naming the shape.
pub fn tosca_eval(
    meshes_dir: &Path,
    settings: &RetrievalSettings,
    cache: &EigenCache,
    seeds: u64,
) -> Result<ToscaEval, BenchError> {
    let tosca_files = protocol::tosca_files(meshes_dir)?;
    let families: Vec<String> = tosca_files.iter().map(|f| f.family.clone()).collect();
    let mut tosca = protocol::load_shapes(tosca_files, &settings.descriptor, cache)?;
    let mut outside = protocol::load_shapes(protocol::outside_files(meshes_dir)?, &settings.descriptor, cache)?;
    let f_tosca = protocol::features(&mut tosca, settings, cache)?;
    let f_outside = protocol::features(&mut outside, settings, cache)?;
    let run = |seed: u64| -> Result<(LooReport, LooReport), BenchError> {
        let mut s = settings.clone();
        s.training.seed = seed;
        let inside = protocol::train(&s, &f_tosca)?;
        let outside = protocol::train(&s, &f_outside)?;
        Ok((
            leave_one_out(&protocol::index(&inside, &s, &f_tosca)?, &families)?,
            leave_one_out(&protocol::index(&outside, &s, &f_tosca)?, &families)?,
        ))
    };
    let (inside, outside_report) = run(settings.training.seed)?;
    let over_seeds = (0..seeds)
        .map(|seed| run(seed).map(|(a, b)| (seed, a.map, b.map)))
        .collect::<Result<_, _>>()?;
    Ok(ToscaEval {
        settings: settings.clone(),
        n_outside: outside.len(),
        inside,
        outside: outside_report,
        over_seeds,
    })
}

/// The markdown section of a [`ToscaEval`].
pub fn tosca_markdown(t: &ToscaEval) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "## TOSCA-76 with the CLI's defaults (`cargo xtask tosca-eval`)\n\n\
         Index = the 76 shapes of `tosca-bcicp-5k/TOSCA_Isometric`; each queries the other 75 (self excluded); \
         relevant = same class (name without trailing digits). Settings: {}.\n",
        serde_json::to_string(&t.settings).unwrap_or_default()
    );
    let _ = writeln!(out, "| vocabulary | mAP | worst class | per class |\n|---|---|---|---|");
    for (label, r) in [
        (
            "trained on the 76 (`wfem retrieval build`; optimistic)".to_string(),
            &t.inside,
        ),
        (
            format!("trained on {} shapes outside (`build --vocab`)", t.n_outside),
            &t.outside,
        ),
    ] {
        let worst = r.worst_family().map_or("–".into(), |(f, v)| format!("{f} {v:.3}"));
        let per: Vec<String> = r.per_family.iter().map(|(f, v)| format!("{f} {v:.3}")).collect();
        let _ = writeln!(out, "| {label} | {:.4} | {worst} | {} |", r.map, per.join(", "));
    }
    if !t.over_seeds.is_empty() {
        let stat = |v: Vec<f64>| {
            let m = v.iter().sum::<f64>() / v.len() as f64;
            let sd = (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / v.len() as f64).sqrt();
            let min = v.iter().copied().fold(f64::INFINITY, f64::min);
            format!("{m:.4} ± {sd:.4} (min {min:.4})")
        };
        let _ = writeln!(
            out,
            "\nOver k-means seeds 0…{}: vocabulary on the 76: {}; outside: {}.",
            t.over_seeds.len() - 1,
            stat(t.over_seeds.iter().map(|x| x.1).collect()),
            stat(t.over_seeds.iter().map(|x| x.2).collect())
        );
    }
    out
}
