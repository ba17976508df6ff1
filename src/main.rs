//! The `wfem` command-line tool (package `wfem-cli`). Without a subcommand it runs `wfem demo`
//! (what `cargo run --release` does). The CLI is private to this binary (module `cli`); the
//! library crates and the facade `wfem` know nothing of it, so a library user never compiles
//! clap, indicatif or the renderer.

use clap::{CommandFactory, Parser, Subcommand};
use std::process::ExitCode;

mod cli;

#[derive(Parser)]
#[command(
    name = "wfem",
    version,
    about = "The wFEM heat kernel on triangle meshes (runs `demo` without a subcommand)"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// Progress bars on standard error: auto (on a terminal only), always (one line per
    /// finished step when not on a terminal) or never.
    #[arg(long, value_enum, global = true, default_value_t = cli::progress::ProgressMode::Auto)]
    progress: cli::progress::ProgressMode,
}

#[derive(Subcommand)]
enum Command {
    /// Mesh statistics and the validation report.
    Info(cli::InfoArgs),
    /// Write the stiffness L, the mass B and the lumped mass D as Matrix Market files.
    Operators(cli::OperatorsArgs),
    /// Apply the heat kernel K_t to a source vertex (--source) or a field (--field).
    Heat(cli::HeatArgs),
    /// Feature-driven approximation f = f_glob + f_loc on persistent critical points (Sect. 4.2).
    Approx(cli::ApproxArgs),
    /// Diffusion distances d_t(i, ·) from one vertex (--from) to every vertex.
    Distance(cli::DistanceArgs),
    /// Geodesic distances from source vertices (--from): fast marching on the intrinsic
    /// Delaunay triangulation, or the heat method (--method heat); --all-pairs for the matrix.
    Geodesic(cli::GeodesicArgs),
    /// The demo: K_t e_i at four scales on a generated mesh, written to ./wfem-out/.
    Demo(cli::DemoArgs),
    /// Heat kernel signature h(i, t) (n × T) of the wFEM or a lumped kernel: exact at the given
    /// or automatic times (selected inversion), or the truncated spectral sum (--method).
    Hks(cli::hks::HksArgs),
    /// Wave kernel signature WKS(i, e) (n × N) on the eigenpairs of the wFEM or a lumped
    /// kernel, at pyFM's energies.
    Wks(cli::wks::WksArgs),
    /// The eigenvalue spectrum λ₁ … λ_m of a surface or a solid and its global signature
    /// (Shape-DNA, Weyl-normalised by the area or the volume).
    Spectrum(cli::spectrum::SpectrumArgs),
    /// Shape retrieval with bags of features: `build` an index, `query` it with a mesh.
    Retrieval(cli::retrieval::RetrievalArgs),
}

fn main() -> ExitCode {
    // Before any other thread: a signal removes the run's temporary files, then ends it.
    cli::signals::install();
    let parsed = Cli::parse();
    let command = parsed.command.unwrap_or(Command::Demo(cli::DemoArgs::default()));
    let quiet = matches!(&command, Command::Demo(a) if a.quiet);
    cli::progress::set_mode(if quiet {
        cli::progress::ProgressMode::Never
    } else {
        parsed.progress
    });
    let args: Vec<String> = std::env::args_os().map(|a| a.to_string_lossy().into_owned()).collect();
    cli::warn_old_spellings(&Cli::command(), &args);
    let mut stdout = std::io::stdout().lock();
    let result = match command {
        Command::Info(a) => cli::info(&a, &mut stdout),
        Command::Operators(a) => cli::operators(&a, &mut stdout),
        Command::Heat(a) => cli::heat(&a, &mut stdout),
        Command::Distance(a) => cli::distance(&a, &mut stdout),
        Command::Geodesic(a) => cli::geodesic(&a, &mut stdout),
        Command::Demo(a) => cli::demo(&a, &mut stdout),
        Command::Approx(a) => cli::approx(&a, &mut stdout),
        Command::Hks(a) => cli::hks::hks(&a, &mut stdout),
        Command::Wks(a) => cli::wks::wks(&a, &mut stdout),
        Command::Spectrum(a) => cli::spectrum::spectrum(&a, &mut stdout),
        Command::Retrieval(a) => cli::retrieval::run(&a, &mut stdout),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // A reader that stopped early (`wfem approx … | head`) is not an error: the outputs
        // are written before the report is printed.
        Err(cli::CliError::Stdout(e)) if e.kind() == std::io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
        Err(e @ cli::CliError::Refused { .. }) => {
            cli::progress::stderr_line(&format!("wfem: {e}"));
            ExitCode::from(cli::EXIT_REFUSED)
        }
        Err(e @ cli::CliError::Unchecked { .. }) => {
            cli::progress::stderr_line(&format!("wfem: {e}"));
            ExitCode::from(cli::EXIT_UNCHECKED)
        }
        Err(e) => {
            cli::progress::stderr_line(&format!("wfem: error: {e}"));
            ExitCode::FAILURE
        }
    }
}
