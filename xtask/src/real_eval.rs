//! `cargo xtask real-eval`: the retrieval defaults (and any variants) on real labelled
//! collections — SHREC'11 (500-face copy) and TOSCA-76 — beside the Shape-DNA baseline, with
//! `wfem retrieval eval`'s measures; writes docs/RETRIEVAL-RESULTS.md (its generated part).

use crate::lab::Variant;
use shape_retrieval::eval::EvalReport;
use shape_retrieval::model::RetrievalSettings;
use shrec_bench::protocol::{self, CloudSampling, EigenCache, ShapeFile};
use shrec_bench::{real, BenchError};
use std::fmt::Write as _;
use std::path::Path;

/// A labelled collection of the evaluation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Collection {
    /// SHREC'11 non-rigid, the 500-face copy: 600 shapes, 30 classes.
    Shrec11,
    /// TOSCA-76 (`tosca-bcicp-5k/TOSCA_Isometric`): 76 shapes, 8 classes.
    Tosca76,
    /// SHREC'11 plus the 20 SHREC'07 four-legged animals as a 31st class.
    Shrec11Fourleg,
    /// TOSCA-76 as point clouds (issue #27): each mesh sampled into 5,000 points uniformly on
    /// its surface (no faces; seeded), described with the robust Laplacian of the cloud.
    Tosca76Clouds,
    /// TOSCA-76's 76 meshes and the same shapes as clouds in one collection (152 shapes, 8
    /// classes): a cloud should find its own mesh first.
    Tosca76Mixed,
    /// TOSCA-76's three people (david, michael, victoria; 39 shapes): classes that are
    /// individuals of one species and differ by build, not by parts (issue #42).
    ToscaPeople,
    /// TOSCA's non-isometric set (`TOSCA_nonIsometric`: gorilla, man, woman; 24 shapes):
    /// each class a body in poses that also stretch it.
    ToscaNonIso,
    /// SHREC'11's man and woman classes (40 shapes).
    Shrec11People,
    /// Generated people ([`shrec_bench::creatures::people_files`]): 10 individuals of
    /// different builds in 8 poses each (80 shapes), written to the temporary folder.
    GeneratedPeople,
    /// The same with builds twice as alike (spread 0.5).
    GeneratedPeopleAlike,
    /// `tosca-people` remeshed shape by shape to 10,000 vertices
    /// ([`shrec_bench::real::remeshed_files`]): as the held-out people of issue #42, each
    /// shape a triangulation of its own at that resolution.
    ToscaPeopleRemeshed,
    /// `tosca-noniso` remeshed likewise.
    ToscaNonIsoRemeshed,
    /// `shrec11-people` remeshed likewise (from 250 vertices: the coarse polyhedra).
    Shrec11PeopleRemeshed,
    /// `generated-people` remeshed likewise (they share one connectivity before).
    GeneratedPeopleRemeshed,
    /// `generated-people-alike` remeshed likewise.
    GeneratedPeopleAlikeRemeshed,
    /// The generated mixed collection ([`shrec_bench::mixed`]): 20 classes of corpus objects,
    /// man-made and organic, genus 0–4, 8 stretched, bulged and remeshed variants each.
    GeneratedMixed,
}

/// TOSCA-76's people (families).
const PEOPLE: [&str; 3] = ["david", "michael", "victoria"];

/// The seed of the TOSCA clouds (mixed with each file's name).
pub const CLOUD_SEED: u64 = 27;

impl Collection {
    /// Every collection.
    pub const ALL: [Collection; 16] = [
        Collection::Shrec11,
        Collection::Tosca76,
        Collection::Shrec11Fourleg,
        Collection::Tosca76Clouds,
        Collection::Tosca76Mixed,
        Collection::ToscaPeople,
        Collection::ToscaNonIso,
        Collection::Shrec11People,
        Collection::GeneratedPeople,
        Collection::GeneratedPeopleAlike,
        Collection::ToscaPeopleRemeshed,
        Collection::ToscaNonIsoRemeshed,
        Collection::Shrec11PeopleRemeshed,
        Collection::GeneratedPeopleRemeshed,
        Collection::GeneratedPeopleAlikeRemeshed,
        Collection::GeneratedMixed,
    ];
    /// Every collection's name.
    pub const NAMES: &'static [&'static str] = &[
        "shrec11",
        "tosca76",
        "shrec11-fourleg",
        "tosca76-clouds",
        "tosca76-mixed",
        "tosca-people",
        "tosca-noniso",
        "shrec11-people",
        "generated-people",
        "generated-people-alike",
        "tosca-people-remeshed",
        "tosca-noniso-remeshed",
        "shrec11-people-remeshed",
        "generated-people-remeshed",
        "generated-people-alike-remeshed",
        "generated-mixed",
    ];

    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Collection::Shrec11 => "shrec11",
            Collection::Tosca76 => "tosca76",
            Collection::Shrec11Fourleg => "shrec11-fourleg",
            Collection::Tosca76Clouds => "tosca76-clouds",
            Collection::Tosca76Mixed => "tosca76-mixed",
            Collection::ToscaPeople => "tosca-people",
            Collection::ToscaNonIso => "tosca-noniso",
            Collection::Shrec11People => "shrec11-people",
            Collection::GeneratedPeople => "generated-people",
            Collection::GeneratedPeopleAlike => "generated-people-alike",
            Collection::ToscaPeopleRemeshed => "tosca-people-remeshed",
            Collection::ToscaNonIsoRemeshed => "tosca-noniso-remeshed",
            Collection::Shrec11PeopleRemeshed => "shrec11-people-remeshed",
            Collection::GeneratedPeopleRemeshed => "generated-people-remeshed",
            Collection::GeneratedPeopleAlikeRemeshed => "generated-people-alike-remeshed",
            Collection::GeneratedMixed => "generated-mixed",
        }
    }

    /// The collection this one is a remeshed copy of.
    pub fn remeshed_from(self) -> Option<Collection> {
        match self {
            Collection::ToscaPeopleRemeshed => Some(Collection::ToscaPeople),
            Collection::ToscaNonIsoRemeshed => Some(Collection::ToscaNonIso),
            Collection::Shrec11PeopleRemeshed => Some(Collection::Shrec11People),
            Collection::GeneratedPeopleRemeshed => Some(Collection::GeneratedPeople),
            Collection::GeneratedPeopleAlikeRemeshed => Some(Collection::GeneratedPeopleAlike),
            _ => None,
        }
    }

    /// How its clouds are sampled.
    fn sampling() -> CloudSampling {
        CloudSampling {
            points: protocol::DEFAULT_CLOUD_POINTS,
            seed: CLOUD_SEED,
        }
    }

    /// The collection of that name.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.name() == name)
    }

    /// The collections of a comma-separated command-line list, in order.
    ///
    /// # Errors
    /// The first unknown name, with the known ones.
    pub fn parse_list(names: &[String]) -> Result<Vec<Self>, String> {
        names
            .iter()
            .map(|c| {
                Self::from_name(c).ok_or_else(|| format!("unknown collection {c:?}: one of {}", Self::NAMES.join(", ")))
            })
            .collect()
    }

    /// A title for the report.
    pub fn title(self) -> &'static str {
        match self {
            Collection::Shrec11 => "SHREC'11 non-rigid, 500-face copy (600 shapes, 30 classes)",
            Collection::Tosca76 => "TOSCA-76 (76 shapes, 8 classes)",
            Collection::Shrec11Fourleg => "SHREC'11 + 20 SHREC'07 four-legged animals as a 31st class",
            Collection::Tosca76Clouds => "TOSCA-76 as point clouds of 5,000 points (76 clouds, 8 classes)",
            Collection::Tosca76Mixed => "TOSCA-76 meshes and clouds together (152 shapes, 8 classes)",
            Collection::ToscaPeople => "TOSCA's three people: david, michael, victoria (39 shapes, 3 classes)",
            Collection::ToscaNonIso => "TOSCA non-isometric: gorilla, man, woman (24 shapes, 3 classes)",
            Collection::Shrec11People => "SHREC'11's man and woman classes (40 shapes, 2 classes)",
            Collection::GeneratedPeople => "Generated people of different builds (80 shapes, 10 classes)",
            Collection::GeneratedPeopleAlike => "Generated people of alike builds, spread 0.5 (80 shapes, 10 classes)",
            Collection::ToscaPeopleRemeshed => {
                "TOSCA's three people, each shape remeshed to 10,000 vertices (39 shapes, 3 classes)"
            }
            Collection::ToscaNonIsoRemeshed => {
                "TOSCA non-isometric, each shape remeshed to 10,000 vertices (24 shapes, 3 classes)"
            }
            Collection::Shrec11PeopleRemeshed => {
                "SHREC'11's man and woman, each shape remeshed to 10,000 vertices (40 shapes, 2 classes)"
            }
            Collection::GeneratedPeopleRemeshed => {
                "Generated people, each shape remeshed to 10,000 vertices (80 shapes, 10 classes)"
            }
            Collection::GeneratedPeopleAlikeRemeshed => {
                "Generated people of alike builds, each shape remeshed to 10,000 vertices (80 shapes, 10 classes)"
            }
            Collection::GeneratedMixed => {
                "Generated mixed collection: 20 corpus objects, rigid and not, 8 variants each (160 shapes, 20 classes)"
            }
        }
    }

    pub(crate) fn files(self, meshes_dir: &Path) -> Result<Vec<ShapeFile>, BenchError> {
        match self {
            Collection::Shrec11 => real::shrec11_files(meshes_dir),
            Collection::Tosca76 => protocol::tosca_files(meshes_dir),
            Collection::Shrec11Fourleg => {
                let mut f = real::shrec11_files(meshes_dir)?;
                f.extend(real::fourleg_files(meshes_dir)?);
                Ok(f)
            }
            Collection::Tosca76Clouds => Ok(Self::clouds(protocol::tosca_files(meshes_dir)?)),
            Collection::Tosca76Mixed => {
                let mut f = protocol::tosca_files(meshes_dir)?;
                f.extend(Self::clouds(f.clone()));
                Ok(f)
            }
            Collection::ToscaPeople => Ok(protocol::tosca_files(meshes_dir)?
                .into_iter()
                .filter(|f| PEOPLE.contains(&f.family.as_str()))
                .collect()),
            Collection::ToscaNonIso => real::noniso_files(meshes_dir),
            Collection::Shrec11People => Ok(real::shrec11_files(meshes_dir)?
                .into_iter()
                .filter(|f| f.family == "man" || f.family == "woman")
                .collect()),
            Collection::GeneratedPeople => {
                shrec_bench::creatures::people_files(&std::env::temp_dir().join("wfem-people-v1-spread1"), 1.0)
            }
            Collection::GeneratedPeopleAlike => {
                shrec_bench::creatures::people_files(&std::env::temp_dir().join("wfem-people-v1-spread0.5"), 0.5)
            }
            Collection::GeneratedMixed => {
                shrec_bench::mixed::mixed_files(meshes_dir, &std::env::temp_dir().join("wfem-mixed-v1"))
            }
            Collection::ToscaPeopleRemeshed
            | Collection::ToscaNonIsoRemeshed
            | Collection::Shrec11PeopleRemeshed
            | Collection::GeneratedPeopleRemeshed
            | Collection::GeneratedPeopleAlikeRemeshed => {
                let base = self
                    .remeshed_from()
                    .ok_or_else(|| BenchError::Data(format!("{} is not a remeshed collection", self.name())))?;
                let dir = std::env::temp_dir().join(format!("wfem-remeshed-v1-{}", base.name()));
                real::remeshed_files(&base.files(meshes_dir)?, &dir, real::REMESH_VERTICES)
            }
        }
    }

    fn clouds(files: Vec<ShapeFile>) -> Vec<ShapeFile> {
        files.iter().map(|f| f.as_cloud(Self::sampling())).collect()
    }

    /// The shapes an honest vocabulary for this collection is trained on (none of them in it).
    fn outside(self, meshes_dir: &Path) -> Result<Vec<ShapeFile>, BenchError> {
        let all = protocol::outside_files(meshes_dir)?;
        Ok(self.alike(match self {
            // The four-legged animals are in the collection itself.
            Collection::Shrec11Fourleg => all
                .into_iter()
                .filter(|f| !f.name.starts_with("shrec07-fourleg"))
                .collect(),
            Collection::ToscaNonIso | Collection::ToscaNonIsoRemeshed => all
                .into_iter()
                .filter(|f| !f.name.contains("TOSCA_nonIsometric"))
                .collect(),
            // Its classes are corpus objects.
            Collection::GeneratedMixed => all
                .into_iter()
                .filter(|f| {
                    !shrec_bench::mixed::MIXED_CLASSES
                        .iter()
                        .any(|(_, file)| *file == f.name)
                })
                .collect(),
            _ => all,
        }))
    }

    /// Training shapes described as this collection's are: clouds are trained on clouds, a
    /// mixed collection on both.
    fn alike(self, all: Vec<ShapeFile>) -> Vec<ShapeFile> {
        match self {
            Collection::Tosca76Clouds => Self::clouds(all),
            Collection::Tosca76Mixed => {
                let mut f = all.clone();
                f.extend(Self::clouds(all));
                f
            }
            _ => all,
        }
    }
}

/// One row of the report: a method with one vocabulary on one collection.
pub struct Row {
    /// The method (variant name or "Shape-DNA baseline").
    pub method: String,
    /// Where its vocabulary was trained.
    pub vocabulary: String,
    /// Its evaluation.
    pub report: EvalReport,
}

/// The evaluation of one collection.
pub struct CollectionResult {
    /// Which.
    pub collection: Collection,
    /// The baseline first, then each variant with the vocabulary on the indexed shapes and
    /// outside.
    pub rows: Vec<Row>,
}

/// Options of [`run`].
pub struct RealEvalOptions<'a> {
    /// Mesh corpus folder.
    pub meshes_dir: &'a Path,
    /// Eigenbasis cache.
    pub cache: &'a EigenCache,
    /// The variants (the first is reported in detail; usually the defaults).
    pub variants: &'a [Variant],
    /// The collections.
    pub collections: &'a [Collection],
    /// Also evaluate with a vocabulary trained outside the collection.
    pub outside: bool,
    /// Also evaluate with a vocabulary trained on this many procedural creatures
    /// ([`shrec_bench::creatures`], written to `creatures_dir`); 0: not.
    pub creatures: u64,
    /// Where the creatures' OFF files are kept.
    pub creatures_dir: &'a Path,
}

/// In a collection holding meshes and the clouds sampled from them (`NAME` and `NAME-cloud`):
/// how many cloud queries have their own mesh as first result, of how many clouds whose mesh
/// is indexed (`None` without such clouds).
pub fn own_mesh_first(report: &EvalReport) -> Option<(usize, usize)> {
    let names: std::collections::HashSet<&str> = report.per_query.iter().map(|q| q.name.as_str()).collect();
    let clouds: Vec<(&str, Option<&str>)> = report
        .per_query
        .iter()
        .filter_map(|q| {
            let mesh = q.name.strip_suffix("-cloud")?;
            names.contains(mesh).then_some((mesh, q.nearest.as_deref()))
        })
        .collect();
    (!clouds.is_empty()).then(|| {
        (
            clouds.iter().filter(|(mesh, nearest)| Some(*mesh) == *nearest).count(),
            clouds.len(),
        )
    })
}

fn line(r: &Row) -> String {
    let m = &r.report.overall;
    let worst: Vec<String> = r
        .report
        .worst_classes()
        .iter()
        .take(3)
        .map(|c| format!("{} {:.2}", c.class, c.measures.map))
        .collect();
    let own = own_mesh_first(&r.report).map_or(String::new(), |(hits, of)| {
        format!(" | cloud queries with their own mesh first {hits}/{of}")
    });
    format!(
        "mAP {:.4} NN {:.4} FT {:.4} ST {:.4} E {:.4} DCG {:.4} | worst {}{own}",
        m.map,
        m.nn,
        m.first_tier,
        m.second_tier,
        m.e_measure,
        m.dcg,
        worst.join(", ")
    )
}

/// Runs every variant on every collection, printing one line per row as it goes.
///
/// # Errors
/// The first failure.
pub fn run(opts: &RealEvalOptions<'_>) -> Result<Vec<CollectionResult>, BenchError> {
    let mut out = Vec::new();
    for &collection in opts.collections {
        let files = collection.files(opts.meshes_dir)?;
        let mut rows = Vec::new();
        let t_base = std::time::Instant::now();
        let baseline = real::shape_dna_baseline(&files, opts.cache)?;
        let per_shape_base = t_base.elapsed().as_secs_f64() / files.len().max(1) as f64;
        rows.push(Row {
            method: "Shape-DNA baseline".into(),
            vocabulary: "–".into(),
            report: baseline,
        });
        println!(
            "[{}] {}: {} ({per_shape_base:.3} s per shape)",
            collection.name(),
            rows[0].method,
            line(&rows[0])
        );
        for v in opts.variants {
            let t0 = std::time::Instant::now();
            let settings: &RetrievalSettings = &v.settings;
            let described = real::describe(files.clone(), settings, opts.cache)?;
            println!(
                "[{}] {}: described in {:.3} s per shape (the baseline {per_shape_base:.3} s; without --cache both include their eigensolves)",
                collection.name(),
                v.name,
                t0.elapsed().as_secs_f64() / files.len().max(1) as f64
            );
            let mut vocabularies: Vec<(String, Option<shape_retrieval::model::VocabularyModel>)> =
                vec![("indexed shapes".into(), None)];
            if opts.outside {
                let outside = real::describe(collection.outside(opts.meshes_dir)?, settings, opts.cache)?;
                let vocabulary = protocol::train(settings, &outside.features)?;
                vocabularies.push((format!("{} outside shapes", outside.files.len()), Some(vocabulary)));
            }
            if opts.creatures > 0 {
                let files = collection.alike(shrec_bench::creatures::creature_files(
                    opts.creatures_dir,
                    opts.creatures,
                )?);
                let creatures = real::describe(files, settings, opts.cache)?;
                let vocabulary = protocol::train(settings, &creatures.features)?;
                vocabularies.push((format!("{} creatures", opts.creatures), Some(vocabulary)));
            }
            for (label, vocabulary) in vocabularies {
                let note = if vocabulary.is_some() {
                    format!("trained on {label}")
                } else {
                    "trained on the indexed shapes (optimistic)".to_string()
                };
                let report = real::evaluate(&described, settings, vocabulary.as_ref(), &note)?;
                let row = Row {
                    method: v.name.clone(),
                    vocabulary: label,
                    report,
                };
                println!(
                    "[{}] {} ({}): {} ({:.0} s)",
                    collection.name(),
                    row.method,
                    row.vocabulary,
                    line(&row),
                    t0.elapsed().as_secs_f64()
                );
                rows.push(row);
            }
        }
        out.push(CollectionResult { collection, rows });
    }
    Ok(out)
}

/// The generated markdown: per collection, one table of every row, the per-class table of the
/// baseline and the first variant, and the first variant's most confused pairs.
pub fn markdown(results: &[CollectionResult]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Generated by `cargo xtask real-eval` (`xtask/src/real_eval.rs`, measures: \
         `shape_retrieval::eval`). Every shape queries all the others from its stored signature \
         (leave-one-out, self excluded); relevant = same class. Shape-DNA baseline: the first 40 \
         non-zero eigenvalues of (L, Voronoi mass) × area / (4πi), L2 (`shrec_bench::real`).\n"
    );
    for r in results {
        let _ = writeln!(s, "## {}\n", r.collection.title());
        let _ = writeln!(
            s,
            "| method | vocabulary | mAP | NN | FT | ST | E | DCG | worst classes (mAP) |\n|---|---|---|---|---|---|---|---|---|"
        );
        for row in &r.rows {
            let m = &row.report.overall;
            let worst: Vec<String> = row
                .report
                .worst_classes()
                .iter()
                .take(3)
                .map(|c| format!("{} {:.2}", c.class, c.measures.map))
                .collect();
            let _ = writeln!(
                s,
                "| {} | {} | {:.4} | {:.4} | {:.4} | {:.4} | {:.4} | {:.4} | {} |",
                row.method,
                row.vocabulary,
                m.map,
                m.nn,
                m.first_tier,
                m.second_tier,
                m.e_measure,
                m.dcg,
                worst.join(", ")
            );
        }
        let own: Vec<String> = r
            .rows
            .iter()
            .filter_map(|row| {
                own_mesh_first(&row.report).map(|(hits, of)| format!("{} ({}) {hits}/{of}", row.method, row.vocabulary))
            })
            .collect();
        if !own.is_empty() {
            let _ = writeln!(
                s,
                "\nCloud queries whose first result is their own mesh: {}.",
                own.join("; ")
            );
        }
        if let (Some(base), Some(first)) = (r.rows.first(), r.rows.get(1)) {
            let _ = writeln!(
                s,
                "\nPer class (mAP / NN / FT): {} ({}) against the baseline.\n",
                first.method, first.vocabulary
            );
            let _ = writeln!(s, "| class | {} | baseline |\n|---|---|---|", first.method);
            for c in &first.report.per_class {
                let b = base.report.per_class.iter().find(|x| x.class == c.class);
                let f =
                    |m: &shape_retrieval::eval::Measures| format!("{:.3} / {:.2} / {:.3}", m.map, m.nn, m.first_tier);
                let _ = writeln!(
                    s,
                    "| {} | {} | {} |",
                    c.class,
                    f(&c.measures),
                    b.map_or("–".into(), |b| f(&b.measures))
                );
            }
            if !first.report.confusions.is_empty() {
                let pairs: Vec<String> = first
                    .report
                    .confusions
                    .iter()
                    .map(|c| format!("{} → {} {:.3}", c.query, c.retrieved, c.share))
                    .collect();
                let _ = writeln!(
                    s,
                    "\nMost confused ({}; share of the query class's first-tier places): {}.\n",
                    first.method,
                    pairs.join(", ")
                );
            }
        }
    }
    s
}

/// Marker line after which docs/RETRIEVAL-RESULTS.md is generated.
pub const GENERATED_MARKER: &str = "<!-- generated by cargo xtask real-eval: everything below is rewritten -->";

/// Replaces the generated part of `path` (after [`GENERATED_MARKER`]; the whole file gets a
/// marker if it has none) with `generated`.
///
/// # Errors
/// Reading or writing the file.
pub fn write_generated(path: &Path, generated: &str) -> Result<(), Box<dyn std::error::Error>> {
    let head = match std::fs::read_to_string(path) {
        Ok(text) => match text.find(GENERATED_MARKER) {
            Some(i) => text[..i].to_string(),
            None => format!("{text}\n"),
        },
        Err(_) => "# Retrieval on real collections\n\n".to_string(),
    };
    let text = format!("{head}{GENERATED_MARKER}\n\n{generated}");
    mesh_fem::io::write_atomic(path, |w| w.write_all(text.as_bytes()))?;
    Ok(())
}
