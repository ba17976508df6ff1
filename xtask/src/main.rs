//! Project chores: `cargo xtask <command>`.
use clap::Parser;
use shrec_bench::synth::{generate, Class, GenerateOptions, DEFAULT_SHAPES};
use std::path::{Path, PathBuf};

#[derive(Parser)]
#[command(name = "xtask", about = "wfem project chores")]
enum Cmd {
    /// Print the version of the workspace.
    Version,
    /// Write procedural creatures (`shrec_bench::creatures`) as OFF files.
    Creatures {
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// Number of creatures (seeds 0..count).
        #[arg(long, default_value_t = 48)]
        count: u64,
        /// Icosphere level (10·4^level + 2 vertices).
        #[arg(long, default_value_t = 5)]
        level: u32,
    },
    /// Generate the synthetic SHREC'10-style benchmark (see docs/SHREC.md).
    Shrec {
        /// Mesh corpus folder (default: $WFEM_MESHES or the shared corpus).
        #[arg(long)]
        meshes: Option<PathBuf>,
        /// Output folder.
        #[arg(long, default_value = "data/shrec")]
        out: PathBuf,
        /// Comma-separated base shapes (`cat` = the null pose cat0; `cat3` = that pose).
        #[arg(long, value_delimiter = ',')]
        shapes: Option<Vec<String>>,
        /// Comma-separated classes (default: all): isometry, topology, microholes, holes,
        /// scale, localscale, noise, shotnoise, sampling.
        #[arg(long, value_delimiter = ',')]
        classes: Option<Vec<String>>,
        /// Strengths: a range `1..5`, a list `1,3,5` or one number.
        #[arg(long, default_value = "1..5")]
        strengths: String,
        /// Global seed.
        #[arg(long, default_value_t = 2010)]
        seed: u64,
    },
    /// Evaluate DHK1–3 / SI-HKS, SHK1/2 and Shape Google retrieval on the SHREC-style data
    /// (generated into --data if missing) and write a markdown report.
    ShrecEval {
        /// Data folder (reused if its manifest covers the subset).
        #[arg(long)]
        data: Option<PathBuf>,
        /// Report file (default: print to stdout).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Which subset to run.
        #[arg(long, default_value = "default")]
        subset: shrec_bench::eval::Subset,
        /// Mesh corpus folder (generation, clean and outside collections).
        #[arg(long)]
        meshes: Option<PathBuf>,
        /// Cache eigenbases in this folder (reruns then skip the eigensolves).
        #[arg(long)]
        cache: Option<PathBuf>,
    },
    /// TOSCA-76 leave-one-out retrieval with the CLI's defaults (or --settings), vocabulary
    /// trained on the 76 and outside them; prints a markdown section.
    ToscaEval {
        /// Mesh corpus folder.
        #[arg(long)]
        meshes: Option<PathBuf>,
        /// Retrieval settings as JSON (partial; missing fields take the defaults).
        #[arg(long)]
        settings: Option<PathBuf>,
        /// Also report the spread over k-means seeds 0 .. N.
        #[arg(long, default_value_t = 5)]
        seeds: u64,
        /// Cache eigenbases in this folder.
        #[arg(long)]
        cache: Option<PathBuf>,
        /// Report file (default: print to stdout).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Retrieval experiments: evaluates settings variants on TOSCA-76 (and the SHREC data).
    RetrievalLab {
        /// Variants: JSON array of {"name": …, "settings": {…}} (partial settings).
        #[arg(long)]
        variants: PathBuf,
        /// SHREC data folder (optional).
        #[arg(long)]
        shrec: Option<PathBuf>,
        /// Mesh corpus folder.
        #[arg(long)]
        meshes: Option<PathBuf>,
        /// Spread over k-means seeds 0 .. N.
        #[arg(long, default_value_t = 0)]
        seeds: u64,
        /// Cache eigenbases in this folder.
        #[arg(long)]
        cache: Option<PathBuf>,
    },
    /// Retrieval on real labelled collections (SHREC'11 500-face copy, TOSCA-76) with the
    /// defaults (or --variants) beside the Shape-DNA baseline; writes docs/RETRIEVAL-RESULTS.md.
    RealEval {
        /// Mesh corpus folder.
        #[arg(long)]
        meshes: Option<PathBuf>,
        /// Cache eigenbases in this folder.
        #[arg(long)]
        cache: Option<PathBuf>,
        /// Variants: JSON array of {"name": …, "settings": {…}} (partial settings laid over the
        /// defaults); without it, the defaults alone.
        #[arg(long)]
        variants: Option<PathBuf>,
        /// Comma-separated collections: shrec11, tosca76, shrec11-fourleg, tosca76-clouds,
        /// tosca76-mixed, tosca-people, tosca-noniso, shrec11-people, generated-people,
        /// generated-people-alike, and the people remeshed shape by shape to 10,000 vertices
        /// (`NAME-remeshed` of the five people sets; written to the system's temporary folder,
        /// `wfem-remeshed-v1-NAME`, where files already there are reused).
        #[arg(long, value_delimiter = ',', default_value = "shrec11,tosca76")]
        collections: Vec<String>,
        /// Also evaluate with a vocabulary trained on shapes outside the collection.
        #[arg(long)]
        outside: bool,
        /// Also evaluate with a vocabulary trained on this many procedural creatures
        /// (`cargo xtask creatures`; written to the system's temporary folder, `wfem-creatures`,
        /// where files already there are reused: delete it after changing the generator).
        #[arg(long, default_value_t = 0)]
        creatures: u64,
        /// Report file whose generated part is rewritten (default: print only).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// How the bags and the global spectrum are best combined (issue #42): every label-free
    /// rule and weight on every collection, with the leave-one-collection-out table.
    FusionLab {
        /// Mesh corpus folder.
        #[arg(long)]
        meshes: Option<PathBuf>,
        /// Cache eigenbases in this folder.
        #[arg(long)]
        cache: Option<PathBuf>,
        /// Comma-separated collections (those of real-eval); by default every dev set: the eight
        /// of issue #42, the five people sets remeshed shape by shape, the generated mixed
        /// collection and TOSCA-76 as point clouds.
        #[arg(
            long,
            value_delimiter = ',',
            default_value = "shrec11,tosca76,shrec11-fourleg,tosca-people,tosca-noniso,shrec11-people,generated-people,generated-people-alike,tosca-people-remeshed,tosca-noniso-remeshed,shrec11-people-remeshed,generated-people-remeshed,generated-people-alike-remeshed,generated-mixed,tosca76-clouds"
        )]
        collections: Vec<String>,
        /// Write the raw scores here (JSON).
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// Measure and write the benchmark report: DIR/BENCHMARKS.md (generated section) and
    /// DIR/bench/*.svg. Full run: 10K/41K/164K vertices (see docs/BENCHMARKS.md); with
    /// `--peers`, then the peers table: wfem's CLI against scipy/libigl, whole process
    /// (xtask/src/peers.rs).
    Bench {
        /// 2.5K/10K/41K vertices: under 5 minutes on 2 cores (without `--peers`).
        #[arg(long, conflicts_with = "smoke")]
        quick: bool,
        /// Tiny meshes (162/642 vertices): checks the pipeline in seconds.
        #[arg(long)]
        smoke: bool,
        /// Add the 655K-vertex mesh to the full run.
        #[arg(long, conflicts_with_all = ["quick", "smoke"])]
        large: bool,
        /// Output folder (BENCHMARKS.md and bench/*.svg).
        #[arg(long, default_value = "docs")]
        out: PathBuf,
        /// Also run the peers table (wfem's CLI against scipy/libigl, whole process; needs
        /// Python and the pinned benches/peers/requirements.txt, installed into a venv on first
        /// use): a stage of its own, since the peers take longer than wfem.
        #[arg(long, conflicts_with = "peers_only")]
        peers: bool,
        /// Only the peers table (rewrites only its block of BENCHMARKS.md).
        #[arg(long)]
        peers_only: bool,
    },
    /// The `wfem` Python wheel (abi3: one wheel for CPython >= 3.10; maturin, release profile)
    /// into target/wheels: `pip install target/wheels/wfem-*.whl`.
    Wheel,
    /// The feature-driven approximation f = f_glob + f_loc (paper Sect. 4.2, Fig. 12–13) on
    /// real meshes, smooth and noisy maps, default beside the paper's formula; writes
    /// docs/APPROX-RESULTS.md.
    ApproxEval {
        /// Mesh corpus folder.
        #[arg(long)]
        meshes: Option<PathBuf>,
        /// Report file (default: print to stdout).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Only the small cases (the ones the test suites use).
        #[arg(long)]
        small: bool,
    },
    /// The whole test suite, Rust and Python (`cargo test-all`, README's test command):
    /// `cargo test --workspace --locked`, then the `wfem` Python package built into a venv
    /// under the target directory and its pytest suite.
    TestAll {
        /// Only the Python suite.
        #[arg(long, conflicts_with = "rust_only")]
        python_only: bool,
        /// Only the Rust suite.
        #[arg(long)]
        rust_only: bool,
        /// Extra pytest arguments (after `--`).
        #[arg(last = true)]
        pytest_args: Vec<String>,
    },
}

fn parse_strengths(text: &str) -> Result<Vec<u8>, String> {
    let bad = || format!("bad --strengths {text:?}: use e.g. 1..5, 2..=4 or 1,3,5");
    if let Some((a, b)) = text.split_once("..") {
        let b = b.trim_start_matches('=');
        let (a, b): (u8, u8) = (
            a.trim().parse().map_err(|_| bad())?,
            b.trim().parse().map_err(|_| bad())?,
        );
        return Ok((a..=b).collect());
    }
    text.split(',').map(|s| s.trim().parse().map_err(|_| bad())).collect()
}

fn eigen_cache(dir: Option<PathBuf>) -> Result<shrec_bench::protocol::EigenCache, shrec_bench::BenchError> {
    match dir {
        Some(d) => shrec_bench::protocol::EigenCache::in_dir(&d),
        None => Ok(shrec_bench::protocol::EigenCache::none()),
    }
}

/// Writes a report atomically to `out`, or prints it.
fn emit(text: &str, out: Option<PathBuf>) -> Result<(), Box<dyn std::error::Error>> {
    match out {
        Some(path) => {
            mesh_fem::io::write_atomic(&path, |w| w.write_all(text.as_bytes()))?;
            println!("wrote {}", path.display());
        }
        None => print!("{text}"),
    }
    Ok(())
}

/// The folder given, or the shared real meshes (`wfem_corpus::meshes_dir`).
fn meshes_or_corpus(meshes: Option<PathBuf>) -> Result<PathBuf, Box<dyn std::error::Error>> {
    Ok(match meshes {
        Some(d) => d,
        None => wfem_corpus::meshes_dir()?,
    })
}

/// `cargo xtask bench`: the report, then (with `--peers`) the peers table.
fn bench(
    setting: xtask::bench::Setting,
    large: bool,
    out: &Path,
    peers: bool,
    peers_only: bool,
) -> Result<(), Box<dyn std::error::Error>> {
    use xtask::bench::{self, BenchOptions};
    use xtask::peers::{self, PeerOptions};
    let start = std::time::Instant::now();
    if !peers_only {
        let options = BenchOptions::for_setting(setting, large);
        let report = bench::run(&options)?;
        for path in bench::write(&report, out)? {
            println!("wrote {}", path.display());
        }
    }
    if peers || peers_only {
        let report = peers::run(&PeerOptions::for_setting(setting, large))?;
        println!("{}", peers::markdown(&report));
        println!("wrote {}", peers::write(&report, out)?.display());
    }
    println!("benchmark report finished in {:.0} s", start.elapsed().as_secs_f64());
    Ok(())
}

/// `cargo xtask approx-eval`: every case of the feature-driven approximation, timed.
fn approx_eval(meshes: Option<PathBuf>, out: Option<PathBuf>, small: bool) -> Result<(), Box<dyn std::error::Error>> {
    let meshes_dir = meshes_or_corpus(meshes)?;
    let cases: &[shrec_bench::approx_eval::ApproxCase] = if small {
        &shrec_bench::approx_eval::SMALL_CASES
    } else {
        &shrec_bench::approx_eval::APPROX_CASES
    };
    let machine = xtask::bench::Machine::probe();
    let start = std::time::Instant::now();
    let mut results = Vec::new();
    for case in cases {
        let t0 = std::time::Instant::now();
        results.push(shrec_bench::approx_eval::evaluate_case(&meshes_dir, case)?);
        eprintln!("{}: {:.1} s", case.name, t0.elapsed().as_secs_f64());
    }
    let text = xtask::approx::markdown(&results, &machine, start.elapsed().as_secs_f64());
    emit(&text, out)
}

/// `cargo xtask real-eval`: the real collections against Shape-DNA.
#[allow(clippy::too_many_arguments)]
fn real_eval(
    meshes: Option<PathBuf>,
    cache: Option<PathBuf>,
    variants: Option<PathBuf>,
    collections: &[String],
    outside: bool,
    creatures: u64,
    out: Option<PathBuf>,
) -> Result<(), Box<dyn std::error::Error>> {
    use xtask::real_eval::{self, Collection, RealEvalOptions};
    let meshes_dir = meshes_or_corpus(meshes)?;
    let variants: Vec<xtask::lab::Variant> = match variants {
        Some(p) => serde_json::from_str(&std::fs::read_to_string(&p)?)?,
        None => serde_json::from_str(r#"[{"name": "default"}]"#)?,
    };
    let collections = Collection::parse_list(collections)?;
    let cache = eigen_cache(cache)?;
    let results = real_eval::run(&RealEvalOptions {
        meshes_dir: &meshes_dir,
        cache: &cache,
        variants: &variants,
        collections: &collections,
        outside,
        creatures,
        creatures_dir: &std::env::temp_dir().join("wfem-creatures"),
    })?;
    let text = real_eval::markdown(&results);
    match out {
        Some(path) => {
            real_eval::write_generated(&path, &text)?;
            println!("wrote {}", path.display());
        }
        None => print!("{text}"),
    }
    Ok(())
}

/// `cargo xtask shrec`: the SHREC'10-style transformed shapes with ground truth.
fn shrec(
    meshes: Option<PathBuf>,
    out: &Path,
    shapes: Option<Vec<String>>,
    classes: Option<Vec<String>>,
    strengths: &str,
    seed: u64,
) -> Result<(), Box<dyn std::error::Error>> {
    let meshes_dir = meshes_or_corpus(meshes)?;
    let shapes = shapes.unwrap_or_else(|| DEFAULT_SHAPES.iter().map(|s| s.to_string()).collect());
    let classes = match classes {
        Some(names) => names
            .iter()
            .map(|n| Class::from_name(n))
            .collect::<Result<Vec<_>, _>>()?,
        None => Class::ALL.to_vec(),
    };
    let opts = GenerateOptions {
        meshes_dir,
        out_dir: out.to_path_buf(),
        shapes,
        classes,
        strengths: parse_strengths(strengths)?,
        seed,
    };
    let manifest = generate(&opts)?;
    println!(
        "wrote {} null shapes and {} transformed shapes to {} (manifest.json)",
        manifest.bases.len(),
        manifest.outputs.len(),
        out.display()
    );
    Ok(())
}

fn run(cmd: Cmd) -> Result<(), Box<dyn std::error::Error>> {
    match cmd {
        Cmd::Version => println!("wfem xtask {}", env!("CARGO_PKG_VERSION")),
        Cmd::Creatures { out, count, level } => {
            std::fs::create_dir_all(&out)?;
            for seed in 0..count {
                let mesh = shrec_bench::creatures::creature(seed, level)?;
                mesh_fem::io::write_mesh(&out.join(format!("creature{seed:03}.off")), &mesh)?;
            }
        }
        Cmd::Shrec {
            meshes,
            out,
            shapes,
            classes,
            strengths,
            seed,
        } => shrec(meshes, &out, shapes, classes, &strengths, seed)?,
        Cmd::ShrecEval {
            data,
            out,
            subset,
            meshes,
            cache,
        } => {
            let data_dir = data.unwrap_or_else(|| PathBuf::from(format!("data/shrec/eval-{}", subset.name())));
            let meshes_dir = meshes_or_corpus(meshes)?;
            let report = shrec_bench::eval::run(&shrec_bench::eval::EvalOptions {
                data_dir,
                meshes_dir,
                subset,
                seed: 2010,
                cache: eigen_cache(cache)?,
            })?;
            emit(&shrec_bench::eval::markdown(&report), out)?;
        }
        Cmd::ToscaEval {
            meshes,
            settings,
            seeds,
            cache,
            out,
        } => {
            let meshes_dir = meshes_or_corpus(meshes)?;
            let settings: shape_retrieval::model::RetrievalSettings = match settings {
                Some(p) => serde_json::from_str(&std::fs::read_to_string(&p)?)?,
                None => Default::default(),
            };
            let t = shrec_bench::eval::tosca_eval(&meshes_dir, &settings, &eigen_cache(cache)?, seeds)?;
            emit(&shrec_bench::eval::tosca_markdown(&t), out)?;
        }
        Cmd::RetrievalLab {
            variants,
            shrec,
            meshes,
            seeds,
            cache,
        } => {
            let variants: Vec<xtask::lab::Variant> = serde_json::from_str(&std::fs::read_to_string(&variants)?)?;
            let meshes_dir = meshes_or_corpus(meshes)?;
            let cache = eigen_cache(cache)?;
            for v in &variants {
                xtask::lab::run_variant(v, &meshes_dir, shrec.as_deref(), &cache, seeds)?;
            }
        }
        Cmd::RealEval {
            meshes,
            cache,
            variants,
            collections,
            outside,
            creatures,
            out,
        } => real_eval(meshes, cache, variants, &collections, outside, creatures, out)?,
        Cmd::FusionLab {
            meshes,
            cache,
            collections,
            json,
        } => {
            use xtask::real_eval::Collection;
            let meshes_dir = meshes_or_corpus(meshes)?;
            let collections = Collection::parse_list(&collections)?;
            let cache = eigen_cache(cache)?;
            print!(
                "{}",
                xtask::fusion_lab::run(&meshes_dir, &cache, &collections, json.as_deref())?
            );
        }
        Cmd::Bench {
            quick,
            smoke,
            large,
            out,
            peers,
            peers_only,
        } => {
            use xtask::bench::Setting;
            let setting = if smoke {
                Setting::Smoke
            } else if quick {
                Setting::Quick
            } else {
                Setting::Full
            };
            bench(setting, large, &out, peers, peers_only)?;
        }
        Cmd::Wheel => {
            let wheel = xtask::wheel::build()?;
            println!("{}", wheel.display());
            println!(
                "install: pip install '{}' (extras: '{}[batch]')",
                wheel.display(),
                wheel.display()
            );
        }
        Cmd::ApproxEval { meshes, out, small } => approx_eval(meshes, out, small)?,
        Cmd::TestAll {
            python_only,
            rust_only,
            pytest_args,
        } => xtask::test_all::run(&xtask::test_all::TestAllOptions {
            python_only,
            rust_only,
            pytest_args,
        })?,
    }
    Ok(())
}

fn main() {
    if let Err(e) = run(Cmd::parse()) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
