//! `cargo xtask fusion-lab`: how the bags and a global spectral signature are best combined
//! (issue #42), chosen so that it carries over. Every collection is described **once** with
//! the defaults plus the Weyl-normalised Shape-DNA of the wFEM spectrum (`λ_i A / 4πi`,
//! i = 1 … k − 1, from the eigenpairs the descriptors already use); the bag and spectrum
//! distance matrices are then combined by every candidate rule (none needs labels) and
//! scored. The leave-one-collection-out table chooses, for each collection, the candidate
//! best on all the others and scores it on the one left out.

use crate::real_eval::Collection;
use faer::Mat;
use shape_retrieval::eval::{evaluate_distances, Measures};
use shape_retrieval::global::GlobalKind;
use shape_retrieval::model::{GlobalSignature, RetrievalSettings};
use shrec_bench::protocol::{self, EigenCache};
use shrec_bench::{real, BenchError};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// The weights tried for the global signature's normalised distance.
pub const WEIGHTS: [f64; 9] = [0.125, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 4.0, 8.0];
/// The numbers of eigenvalues tried.
pub const EIGENVALUES: [usize; 4] = [10, 20, 40, 99];

/// One collection's matrices.
struct Matrices {
    names: Vec<String>,
    classes: Vec<String>,
    bag: Mat<f64>,
    /// (label, matrix) of each global signature tried.
    globals: Vec<(String, Mat<f64>)>,
    /// The Shape-DNA baseline (lumped mass, raw mesh, 40 eigenvalues).
    baseline: Mat<f64>,
}

/// How two distances are combined (none of them uses labels).
#[derive(Clone, Copy, Debug)]
enum Rule {
    /// Each row divided by its own median (over the other shapes): the query's distances
    /// to the index, put on one scale.
    QueryMedian,
    /// Each matrix divided by its median over all pairs of the index.
    IndexMedian,
    /// The ranks in each row (Borda count).
    Rank,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        1.0
    } else {
        v[v.len() / 2].max(1e-300)
    }
}

fn off_diagonal_row(m: &Mat<f64>, q: usize) -> Vec<f64> {
    (0..m.ncols()).filter(|&j| j != q).map(|j| m[(q, j)]).collect()
}

fn normalised(m: &Mat<f64>, rule: Rule) -> Mat<f64> {
    let n = m.nrows();
    match rule {
        Rule::QueryMedian => {
            let med: Vec<f64> = (0..n).map(|q| median(off_diagonal_row(m, q))).collect();
            Mat::from_fn(n, n, |i, j| m[(i, j)] / med[i])
        }
        Rule::IndexMedian => {
            let all: Vec<f64> = (0..n).flat_map(|q| off_diagonal_row(m, q)).collect();
            let med = median(all);
            Mat::from_fn(n, n, |i, j| m[(i, j)] / med)
        }
        Rule::Rank => {
            let mut r = Mat::zeros(n, n);
            for q in 0..n {
                let mut order: Vec<usize> = (0..n).collect();
                order.sort_by(|&a, &b| m[(q, a)].total_cmp(&m[(q, b)]).then(a.cmp(&b)));
                for (k, &j) in order.iter().enumerate() {
                    r[(q, j)] = k as f64 / n as f64;
                }
            }
            r
        }
    }
}

fn describe(collection: Collection, meshes_dir: &Path, cache: &EigenCache) -> Result<Matrices, BenchError> {
    let files = collection.files(meshes_dir)?;
    let mut settings = RetrievalSettings::default();
    let m = settings.descriptor.eigenpairs - 1;
    settings.bags.global = Some(GlobalSignature {
        kind: GlobalKind::WeylShapeDna,
        eigenvalues: m,
        weight: 0.0,
    });
    let described = real::describe(files.clone(), &settings, cache)?;
    let vocabulary = protocol::train(&settings, &described.features)?;
    let index = protocol::index(&vocabulary, &settings, &described.features)?;
    let entries = index.entries();
    let n = entries.len();
    let distance = settings.bags.distance;
    let bag = Mat::from_fn(n, n, |i, j| {
        distance
            .between(&entries[i].signature.bag, &entries[j].signature.bag)
            .unwrap_or(f64::INFINITY)
    });
    let mut globals = Vec::new();
    for &k in &EIGENVALUES {
        let k = k.min(m);
        let weyl = |i: usize| &entries[i].signature.global[..k];
        globals.push((
            format!("weyl{k}"),
            Mat::from_fn(n, n, |i, j| GlobalKind::WeylShapeDna.distance(weyl(i), weyl(j))),
        ));
        let log: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                weyl(i)
                    .iter()
                    .enumerate()
                    .map(|(t, g)| (g * 4.0 * std::f64::consts::PI * (t + 1) as f64).max(1e-300).ln())
                    .collect()
            })
            .collect();
        globals.push((
            format!("log{k}"),
            Mat::from_fn(n, n, |i, j| GlobalKind::LogShapeDna.distance(&log[i], &log[j])),
        ));
    }
    let dna = real::shape_dna_signatures(&files, cache)?;
    let baseline = Mat::from_fn(n, n, |i, j| GlobalKind::WeylShapeDna.distance(&dna[i], &dna[j]));
    globals.push(("dna40".to_string(), baseline.clone()));
    Ok(Matrices {
        names: files.iter().map(|f| f.name.clone()).collect(),
        classes: files.iter().map(|f| f.family.clone()).collect(),
        bag,
        globals,
        baseline,
    })
}

/// Label-free contrast of a distance matrix: the mean over rows of the k-th smallest
/// off-diagonal distance over the row's median (small: tight neighbourhoods against the
/// spread of the collection).
fn contrast(m: &Mat<f64>, k: usize) -> f64 {
    let n = m.nrows();
    (0..n)
        .map(|q| {
            let mut row = off_diagonal_row(m, q);
            row.sort_by(f64::total_cmp);
            match row.len() {
                0 => 0.0,
                len => row[(k - 1).min(len - 1)] / row[len / 2].max(1e-300),
            }
        })
        .sum::<f64>()
        / n as f64
}

fn score(m: &Matrices, d: &Mat<f64>) -> Result<Measures, BenchError> {
    Ok(evaluate_distances(&m.names, &m.classes, d.as_ref(), "lab")
        .map_err(BenchError::retrieval("fusion lab"))?
        .overall)
}

/// Every candidate's overall measures on one collection, by candidate name (`bags`,
/// `baseline`, `GLOBAL` alone, `RULE:GLOBAL:w`).
fn candidates(m: &Matrices) -> Result<BTreeMap<String, Measures>, BenchError> {
    let mut out = BTreeMap::new();
    out.insert("bags".to_string(), score(m, &m.bag)?);
    out.insert("shape-dna-baseline".to_string(), score(m, &m.baseline)?);
    let stat = |c: f64| Measures {
        map: c,
        nn: 0.0,
        first_tier: 0.0,
        second_tier: 0.0,
        e_measure: 0.0,
        dcg: 0.0,
    };
    for k in [1, 3, 5] {
        out.insert(format!("contrast bags {k}"), stat(contrast(&m.bag, k)));
        for (label, g) in &m.globals {
            out.insert(format!("contrast {label} {k}"), stat(contrast(g, k)));
        }
    }
    for (label, g) in &m.globals {
        out.insert(format!("{label} alone"), score(m, g)?);
        for (rname, rule) in [
            ("qmed", Rule::QueryMedian),
            ("imed", Rule::IndexMedian),
            ("rank", Rule::Rank),
        ] {
            let nb = normalised(&m.bag, rule);
            let ng = normalised(g, rule);
            for w in WEIGHTS {
                let n = nb.nrows();
                let d = Mat::from_fn(n, n, |i, j| nb[(i, j)] + w * ng[(i, j)]);
                out.insert(format!("{rname}:{label}:{w}"), score(m, &d)?);
            }
        }
    }
    Ok(out)
}

/// Runs the lab on `collections`; returns the markdown report and writes the raw scores
/// (`{collection: {candidate: [mAP, NN, FT, ST, DCG]}}`) to `json` when given.
///
/// # Errors
/// The first failure.
pub fn run(
    meshes_dir: &Path,
    cache: &EigenCache,
    collections: &[Collection],
    json: Option<&Path>,
) -> Result<String, Box<dyn std::error::Error>> {
    let mut all: BTreeMap<String, BTreeMap<String, Measures>> = BTreeMap::new();
    for &c in collections {
        let t0 = std::time::Instant::now();
        let m = describe(c, meshes_dir, cache)?;
        let scores = candidates(&m)?;
        println!(
            "[{}] bags {:.4} baseline {:.4} ({} candidates, {:.0} s)",
            c.name(),
            scores["bags"].map,
            scores["shape-dna-baseline"].map,
            scores.len(),
            t0.elapsed().as_secs_f64()
        );
        all.insert(c.name().to_string(), scores);
    }
    if let Some(path) = json {
        let raw: BTreeMap<&String, BTreeMap<&String, [f64; 5]>> = all
            .iter()
            .map(|(c, s)| {
                (
                    c,
                    s.iter()
                        .map(|(k, m)| (k, [m.map, m.nn, m.first_tier, m.second_tier, m.dcg]))
                        .collect(),
                )
            })
            .collect();
        mesh_fem::io::write_atomic(path, |w| {
            w.write_all(
                serde_json::to_string_pretty(&raw)
                    .map_err(std::io::Error::other)?
                    .as_bytes(),
            )
        })?;
    }
    Ok(report(&all))
}

/// The mean over `cols` of a candidate's mAP (−∞ if any is missing).
fn mean_map(all: &BTreeMap<String, BTreeMap<String, Measures>>, cols: &[&String], cand: &str) -> f64 {
    let v: Vec<f64> = cols
        .iter()
        .map(|c| all[*c].get(cand).map_or(f64::NEG_INFINITY, |m| m.map))
        .collect();
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// The report: the best candidate on all collections together, its rows, and the
/// leave-one-collection-out table.
pub fn report(all: &BTreeMap<String, BTreeMap<String, Measures>>) -> String {
    let mut s = String::new();
    let cols: Vec<&String> = all.keys().collect();
    let Some(first) = cols.first() else {
        return s;
    };
    // The contrasts are statistics of a distance, not candidates.
    let names: Vec<&String> = all[*first].keys().filter(|c| !c.starts_with("contrast")).collect();
    let best = |among: &[&String]| -> String {
        names
            .iter()
            .max_by(|a, b| mean_map(all, among, a).total_cmp(&mean_map(all, among, b)))
            .map(|c| c.to_string())
            .unwrap_or_default()
    };
    let _ = writeln!(
        s,
        "| candidate | {} | mean |",
        cols.iter().map(|c| c.as_str()).collect::<Vec<_>>().join(" | ")
    );
    let _ = writeln!(s, "|---|{}---|", "---|".repeat(cols.len()));
    let mut shown: Vec<String> = vec!["bags".into(), "shape-dna-baseline".into(), best(&cols)];
    for prefix in ["qmed:", "imed:", "rank:"] {
        if let Some(c) = names
            .iter()
            .filter(|c| c.starts_with(prefix))
            .max_by(|a, b| mean_map(all, &cols, a).total_cmp(&mean_map(all, &cols, b)))
        {
            shown.push(c.to_string());
        }
    }
    let mut seen = std::collections::HashSet::new();
    shown.retain(|c| seen.insert(c.clone()));
    for cand in &shown {
        let cells: Vec<String> = cols
            .iter()
            .map(|c| {
                all[*c]
                    .get(cand)
                    .map_or("–".into(), |m| format!("{:.4} / {:.3}", m.map, m.first_tier))
            })
            .collect();
        let _ = writeln!(
            s,
            "| {cand} | {} | {:.4} |",
            cells.join(" | "),
            mean_map(all, &cols, cand)
        );
    }
    let _ = writeln!(
        s,
        "\nLeave one collection out (chosen on the others by mean mAP, scored on the one left out):\n"
    );
    let _ = writeln!(s, "| left out | chosen on the others | its mAP / FT there | bags | Shape-DNA baseline | holds |\n|---|---|---|---|---|---|");
    for c in &cols {
        let others: Vec<&String> = cols.iter().filter(|x| x != &c).copied().collect();
        if others.is_empty() {
            continue;
        }
        let chosen = best(&others);
        let m = &all[*c];
        let (x, bags, dna) = (&m[&chosen], &m["bags"], &m["shape-dna-baseline"]);
        let holds = x.map >= bags.map && x.map >= dna.map;
        let _ = writeln!(
            s,
            "| {c} | {chosen} | {:.4} / {:.3} | {:.4} / {:.3} | {:.4} / {:.3} | {} |",
            x.map,
            x.first_tier,
            bags.map,
            bags.first_tier,
            dna.map,
            dna.first_tier,
            if holds { "yes" } else { "no" }
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn measures(map: f64) -> Measures {
        Measures {
            map,
            nn: 0.0,
            first_tier: 0.0,
            second_tier: 0.0,
            e_measure: 0.0,
            dcg: 0.0,
        }
    }

    #[test]
    fn normalisations_put_each_row_on_one_scale() {
        let m = Mat::from_fn(3, 3, |i, j| if i == j { 0.0 } else { (1 + i + j) as f64 });
        let q = normalised(&m, Rule::QueryMedian);
        // Row 0: off-diagonal 2, 3 → median (upper) 3.
        assert_eq!(q[(0, 1)], 2.0 / 3.0);
        let r = normalised(&m, Rule::Rank);
        // Row 0 order: 0 (self, 0), 1 (2), 2 (3).
        assert_eq!((r[(0, 0)], r[(0, 1)], r[(0, 2)]), (0.0, 1.0 / 3.0, 2.0 / 3.0));
    }

    #[test]
    fn leave_one_out_chooses_on_the_others_only() {
        // "x" wins on a and b, loses on c: left out c, it is chosen and does not hold there.
        let mut all: BTreeMap<String, BTreeMap<String, Measures>> = BTreeMap::new();
        for (c, bags, x, dna) in [("a", 0.90, 0.95, 0.5), ("b", 0.90, 0.95, 0.5), ("c", 0.90, 0.87, 0.5)] {
            let mut s = BTreeMap::new();
            s.insert("bags".to_string(), measures(bags));
            s.insert("qmed:x:1".to_string(), measures(x));
            s.insert("shape-dna-baseline".to_string(), measures(dna));
            all.insert(c.to_string(), s);
        }
        let text = report(&all);
        assert!(
            text.contains("| c | qmed:x:1 | 0.8700 / 0.000 | 0.9000 / 0.000 | 0.5000 / 0.000 | no |"),
            "{text}"
        );
        assert!(
            text.contains("| a | qmed:x:1 | 0.9500 / 0.000 | 0.9000 / 0.000 | 0.5000 / 0.000 | yes |"),
            "{text}"
        );
    }
}
