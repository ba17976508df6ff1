//! `cargo xtask retrieval-lab`: evaluates retrieval settings variants (the experiments behind
//! docs/SHREC-RESULTS.md) on TOSCA-76 and the synthetic SHREC'10 data, one line per number.

use shape_retrieval::model::RetrievalSettings;
use shrec_bench::protocol::{self, shrec_protocol, EigenCache, ShapeFile};
use shrec_bench::synth::Manifest;
use shrec_bench::BenchError;
use std::path::Path;

/// One named variant.
#[derive(serde::Deserialize)]
pub struct Variant {
    /// Its name.
    pub name: String,
    /// Its settings (partial JSON laid over the defaults' JSON: a missing field takes the
    /// default, even one that a settings file read on its own would take as off).
    #[serde(default, deserialize_with = "over_defaults")]
    pub settings: RetrievalSettings,
}

fn over_defaults<'de, D: serde::Deserializer<'de>>(d: D) -> Result<RetrievalSettings, D::Error> {
    fn merge(base: &mut serde_json::Value, patch: serde_json::Value) {
        match (base, patch) {
            // A tagged variant ("kind") replaces the default as a whole.
            (serde_json::Value::Object(b), serde_json::Value::Object(p)) if !p.contains_key("kind") => {
                for (k, v) in p {
                    match b.get_mut(&k) {
                        Some(slot) => merge(slot, v),
                        None => {
                            b.insert(k, v);
                        }
                    }
                }
            }
            (slot, v) => *slot = v,
        }
    }
    let patch: serde_json::Value = serde::Deserialize::deserialize(d)?;
    let mut base = serde_json::to_value(RetrievalSettings::default()).map_err(serde::de::Error::custom)?;
    merge(&mut base, patch);
    serde_json::from_value(base).map_err(serde::de::Error::custom)
}

fn f3(v: [f64; 5]) -> String {
    v.iter().map(|x| format!("{x:.3}")).collect::<Vec<_>>().join(" ")
}

/// Runs one variant and prints its numbers.
///
/// # Errors
/// The first failure.
pub fn run_variant(
    v: &Variant,
    meshes_dir: &Path,
    shrec: Option<&Path>,
    cache: &EigenCache,
    seeds: u64,
) -> Result<(), BenchError> {
    let (name, settings) = (&v.name, &v.settings);
    let t0 = std::time::Instant::now();
    let tosca = shrec_bench::eval::tosca_eval(meshes_dir, settings, cache, seeds)?;
    for (label, r) in [("76", &tosca.inside), ("outside", &tosca.outside)] {
        let per: Vec<String> = r.per_family.iter().map(|(f, v)| format!("{f} {v:.3}")).collect();
        println!(
            "[{name}] TOSCA-76 vocab {label:>7}: mAP {:.4} | {}",
            r.map,
            per.join(", ")
        );
    }
    if seeds > 0 {
        let stat = |v: Vec<f64>| {
            let m = v.iter().sum::<f64>() / v.len() as f64;
            let min = v.iter().copied().fold(1.0, f64::min);
            format!("{m:.4} (min {min:.4})")
        };
        println!(
            "[{name}] TOSCA-76 over {seeds} seeds: 76 {} | outside {}",
            stat(tosca.over_seeds.iter().map(|x| x.1).collect()),
            stat(tosca.over_seeds.iter().map(|x| x.2).collect())
        );
    }
    if let Some(dir) = shrec {
        let text = std::fs::read_to_string(dir.join("manifest.json")).map_err(|e| BenchError::Data(e.to_string()))?;
        let manifest: Manifest = serde_json::from_str(&text)?;
        let files: Vec<ShapeFile> = protocol::shrec_files(dir, &manifest);
        let mut shapes = protocol::load_shapes(files.clone(), &settings.descriptor, cache)?;
        let tosca_files = protocol::tosca_files(meshes_dir)?;
        let families: Vec<String> = tosca_files.iter().map(|f| f.family.clone()).collect();
        let mut clean = protocol::load_shapes(tosca_files, &settings.descriptor, cache)?;
        let mut outside = protocol::load_shapes(protocol::outside_files(meshes_dir)?, &settings.descriptor, cache)?;
        let fs = protocol::features(&mut shapes, settings, cache)?;
        let fc = protocol::features(&mut clean, settings, cache)?;
        let fo = protocol::features(&mut outside, settings, cache)?;
        let nulls: Vec<_> = files
            .iter()
            .zip(&fs)
            .filter(|(f, _)| f.transform.is_none())
            .map(|(_, x)| x.clone())
            .collect();
        for (label, train) in [("nulls", &nulls), ("outside", &fo)] {
            let vocabulary = protocol::train(settings, train)?;
            let db = protocol::index(&vocabulary, settings, &fs)?;
            let cl = protocol::index(&vocabulary, settings, &fc)?;
            let r = shrec_protocol(&db, &files, Some((&cl, &families)))?;
            let all = |_: &protocol::QueryResult| true;
            println!("[{name}] SHREC ({label:>7} vocab) cum ≤s: {}", f3(r.cumulative(all)));
            println!(
                "[{name}] SHREC ({label:>7} vocab) full db: {}",
                f3(r.cumulative_full(all))
            );
            println!(
                "[{name}] SHREC ({label:>7} vocab) clean:   {}",
                f3(r.cumulative_clean(all))
            );
            if label == "nulls" {
                for t in r.transforms() {
                    println!(
                        "[{name}]   {:<11} cum {} | clean {}",
                        t.name(),
                        f3(r.cumulative(|q| q.transform == t)),
                        f3(r.cumulative_clean(|q| q.transform == t))
                    );
                }
                for f in r.families() {
                    let worst = r
                        .transforms()
                        .into_iter()
                        .map(|t| (r.cumulative(|q| q.family == f && q.transform == t)[2], t.name()))
                        .min_by(|a, b| a.0.total_cmp(&b.0));
                    println!(
                        "[{name}]   {f:<9} cum {} | worst ≤3 {worst:?}",
                        f3(r.cumulative(|q| q.family == f))
                    );
                }
                // Strength-5 queries against the whole database of strength ≤ 5, family × class.
                let transforms = r.transforms();
                println!(
                    "[{name}]   s5 AP     {}",
                    transforms
                        .iter()
                        .map(|t| format!("{:>6.6}", t.name()))
                        .collect::<Vec<_>>()
                        .join(" ")
                );
                for f in r.families() {
                    let cells: Vec<String> = transforms
                        .iter()
                        .map(|&t| {
                            let aps: Vec<f64> = r
                                .queries
                                .iter()
                                .filter(|q| q.family == f && q.transform == t && q.strength == 5)
                                .filter_map(|q| q.ap_cumulative[4])
                                .collect();
                            if aps.is_empty() {
                                format!("{:>6}", "–")
                            } else {
                                format!("{:>6.3}", aps.iter().sum::<f64>() / aps.len() as f64)
                            }
                        })
                        .collect();
                    println!("[{name}]   {f:<9} {}", cells.join(" "));
                }
            }
        }
    }
    println!("[{name}] ({:.0} s)", t0.elapsed().as_secs_f64());
    Ok(())
}
