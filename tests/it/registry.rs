//! The command line takes every choice from the library's registries (issue #26): for each
//! flag that names a choice, `--help` lists exactly the registry's names, every name and alias
//! is accepted, and an unknown name is refused with the list of valid ones.

use super::common::wfem;
use wfem_base::{check_entries, Choice};

/// A flag of a subcommand and the names its registry holds.
struct Flag {
    subcommand: &'static [&'static str],
    flag: &'static str,
    names: Vec<&'static str>,
    aliases: Vec<&'static str>,
}

fn flag<T: Choice>(subcommand: &'static [&'static str], flag: &'static str) -> Flag {
    check_entries::<T>().unwrap();
    Flag {
        subcommand,
        flag,
        names: T::names().collect(),
        aliases: T::entries().iter().flat_map(|e| e.aliases.iter().copied()).collect(),
    }
}

fn flags() -> Vec<Flag> {
    use mesh_fem::validate::RepairStep;
    use mesh_fem::Mass;
    use shape_retrieval::descriptor::Descriptor;
    use shape_retrieval::distance::BagDistance;
    use shape_retrieval::exact::HksMethod;
    use wfem_heat::approx::Coefficients;
    use wfem_heat::distance::DistanceKind;
    use wfem_heat::method::Method;
    vec![
        flag::<Mass>(&["heat"], "--mass"),
        flag::<Method>(&["heat"], "--method"),
        flag::<shifted_solve::backend::Backend>(&["heat"], "--backend"),
        flag::<Up>(&["heat"], "--up"),
        flag::<RepairStep>(&["heat"], "--repair"),
        flag::<Mass>(&["hks"], "--mass"),
        flag::<HksMethod>(&["hks"], "--method"),
        flag::<DistanceKind>(&["distance"], "--kind"),
        flag::<wfem_heat::geodesic::GeodesicMethod>(&["geodesic"], "--method"),
        flag::<Mass>(&["wks"], "--mass"),
        flag::<shape_retrieval::global::GlobalKind>(&["spectrum"], "--kind"),
        flag::<Mass>(&["spectrum"], "--mass"),
        flag::<Coefficients>(&["approx"], "--coefficients"),
        flag::<wfem_heat::approx::NoiseRule>(&["approx"], "--noise"),
        flag::<Mass>(&["approx"], "--mass"),
        flag::<mesh_fem::Lumping>(&["operators"], "--lumped"),
        flag::<Descriptor>(&["retrieval", "build"], "--descriptor"),
        flag::<BagDistance>(&["retrieval", "build"], "--distance"),
    ]
}

use wfem_render::Up;

/// The possible values `--help` lists for `flag` (clap's long help: a "Possible values:"
/// block of `- name: help` lines under the flag).
fn listed(help: &str, flag: &str) -> Vec<String> {
    let mut lines = help.lines().skip_while(|l| !l.trim_start().starts_with(flag));
    let mut out = Vec::new();
    let mut in_values = false;
    for line in lines.by_ref().skip(1) {
        let t = line.trim();
        if t.starts_with("Possible values:") {
            in_values = true;
            continue;
        }
        if in_values {
            match t.strip_prefix("- ") {
                Some(rest) => out.push(rest.split(':').next().unwrap_or("").trim().to_string()),
                None if t.is_empty() => break,
                None => {}
            }
        } else if t.starts_with("--") || t.starts_with("-o") {
            break;
        }
    }
    out
}

#[test]
fn cli_help_lists_exactly_the_library_names() {
    for f in flags() {
        let mut args: Vec<&str> = f.subcommand.to_vec();
        args.push("--help");
        let out = wfem(&args);
        assert!(out.status.success(), "{args:?}");
        let help = String::from_utf8_lossy(&out.stdout);
        let got = listed(&help, f.flag);
        assert_eq!(got, f.names, "{:?} {}: --help lists {got:?}", f.subcommand, f.flag);
    }
}

#[test]
fn cli_refuses_an_unknown_name_with_the_valid_ones() {
    for f in flags() {
        let mut args: Vec<&str> = f.subcommand.to_vec();
        args.extend([f.flag, "no-such-name", "mesh.off"]);
        let out = wfem(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("no-such-name"), "{args:?}: {err}");
        for name in &f.names {
            assert!(err.contains(name), "{args:?}: {name} not listed in {err}");
        }
    }
}

#[test]
fn cli_accepts_every_name_and_alias_at_parse_time() {
    // A missing mesh file is the first error after parsing: every name gets that far.
    for f in flags() {
        for name in f.names.iter().chain(&f.aliases) {
            let mut args: Vec<&str> = f.subcommand.to_vec();
            args.extend([f.flag, name, "/nonexistent/mesh.off"]);
            let out = wfem(&args);
            let err = String::from_utf8_lossy(&out.stderr);
            assert!(
                !err.contains("invalid value"),
                "{:?} {} {name}: refused at parse time: {err}",
                f.subcommand,
                f.flag
            );
        }
    }
}

/// Every name and alias of every registry.
fn all_spellings() -> Vec<&'static str> {
    fn of<T: Choice>(out: &mut Vec<&'static str>) {
        for e in T::entries() {
            out.push(e.name);
            out.extend(e.aliases.iter().copied());
        }
    }
    let mut out = Vec::new();
    of::<mesh_fem::Mass>(&mut out);
    of::<mesh_fem::Lumping>(&mut out);
    of::<mesh_fem::validate::RepairStep>(&mut out);
    of::<mesh_fem::io::FieldFormat>(&mut out);
    of::<shifted_solve::backend::Backend>(&mut out);
    of::<wfem_heat::method::Method>(&mut out);
    of::<wfem_heat::KernelDiagonal>(&mut out);
    of::<wfem_heat::diagonal::DiagonalMethod>(&mut out);
    of::<wfem_heat::distance::DistanceKind>(&mut out);
    of::<wfem_heat::geodesic::GeodesicMethod>(&mut out);
    of::<mesh_fem::Laplacian>(&mut out);
    // (MeshFormat is left out: its "off" is also the word that turns a cleaning step off.)
    of::<mesh_fem::io::volume::VolumeFormat>(&mut out);
    of::<wfem_heat::approx::ScaleSampling>(&mut out);
    of::<shape_retrieval::global::GlobalKind>(&mut out);
    of::<wfem_heat::approx::Coefficients>(&mut out);
    of::<wfem_heat::approx::NoiseRule>(&mut out);
    of::<shape_retrieval::exact::HksMethod>(&mut out);
    of::<shape_retrieval::hks::SpectrumNormalization>(&mut out);
    of::<shape_retrieval::descriptor::Descriptor>(&mut out);
    of::<shape_retrieval::descriptor::FeatureDetector>(&mut out);
    of::<shape_retrieval::distance::BagDistance>(&mut out);
    of::<retrieval_store::metric::StandardMetric>(&mut out);
    of::<Up>(&mut out);
    out
}

/// The string literals of a Rust source that could name a choice: outside comments (`//` to
/// the end of a line), and not a key (`"key": …` in `json!`, the key of `set_item`/`insert`/
/// `get_item`) or the name of a Python parameter (`(py, "param", …)`), which are field and
/// argument names, not choices.
fn literals(source: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut previous = String::new();
    for (i, line) in source.lines().enumerate() {
        let code = match line.find("//") {
            // A `//` inside a string literal (a URL) is rare in these files; good enough.
            Some(p) if !line[..p].ends_with(':') => &line[..p],
            _ => line,
        };
        let mut at = 0;
        while let Some(start) = code[at..].find('"').map(|s| s + at) {
            let Some(len) = code[start + 1..].find('"') else { break };
            let end = start + 1 + len;
            let text = &code[start + 1..end];
            // A call split over lines: the text before the literal is the previous line's.
            let before = match code[..start].trim() {
                "" => previous.as_str(),
                _ => code[..start].trim_end(),
            };
            let after = code[end + 1..].trim_start();
            let key = (after.starts_with(':') && !after.starts_with("::"))
                || [
                    "set_item(",
                    "insert(",
                    "get_item(",
                    "(py,",
                    "py,",
                    "\"command\".into(), json!(",
                ]
                .iter()
                .any(|k| before.ends_with(k));
            if !key {
                out.push((i + 1, text.to_string()));
            }
            at = end + 1;
        }
        if !code.trim().is_empty() {
            previous = code.trim().to_string();
        }
    }
    out
}

/// Issue #26: the command line (`src/cli`) and the Python bindings (`crates/wfem-py/src`) keep
/// no name of a choice as a string literal; they read the names from the library's registries.
#[test]
fn cli_and_bindings_keep_no_choice_names() {
    let spellings = all_spellings();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut found = Vec::new();
    for dir in ["src/cli", "crates/wfem-py/src"] {
        let mut files: Vec<_> = std::fs::read_dir(root.join(dir))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "rs"))
            .collect();
        files.sort();
        for file in files {
            let source = std::fs::read_to_string(&file).unwrap();
            for (line, text) in literals(&source) {
                if spellings.contains(&text.as_str()) {
                    found.push(format!("{}:{line}: \"{text}\"", file.display()));
                }
            }
        }
    }
    assert!(
        found.is_empty(),
        "choice names written out instead of read from a registry:\n{}",
        found.join("\n")
    );
}
