//! Command-line parsing and dispatch. Each subcommand lives in its own file and only turns
//! flags into library calls and prints results.

mod build;
mod demo;
mod export_glb;
mod export_obj;
mod export_tiles;
mod fit_camera;
mod fly;
mod progress;
mod project;
mod register;
mod render;
mod reparam;
mod stats;
mod values;
mod verify;
mod view;
mod view_window;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// cliffmap: better terrain textures on cliffs.
#[derive(Parser, Debug)]
#[command(name = "cliffmap", version, about, long_about = None)]
struct Cli {
    /// Worker threads (default: all cores). Outputs do not depend on it.
    #[arg(long, global = true)]
    threads: Option<usize>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run the whole pipeline on the embedded procedural scene (no data needed).
    Demo(demo::Args),
    /// Build a cell store from a DEM (and an ortho image).
    Build(build::Args),
    /// Reparameterize stretched cells (Degener et al. 2003) and resample their textures.
    Reparam(reparam::Args),
    /// Merge ground photos (known camera poses) into the cell textures of every level.
    Project(project::Args),
    /// Texel-stretch statistics of a store: summary, stats.json and a histogram PNG.
    Stats(stats::Args),
    /// Check every file, mesh and texture of a store; --repair rebuilds damaged cells.
    Verify(verify::Args),
    /// Fit a photo's camera to ground control points (robust Levenberg-Marquardt).
    FitCamera(fit_camera::Args),
    /// Refine rough photo cameras against the store's terrain (no GCPs needed).
    Register(register::Args),
    /// Write one cell's TIN with texture coordinates as Wavefront OBJ.
    ExportObj(export_obj::Args),
    /// Write chosen cells with their best textures as one GLB (Blender, glTF viewers).
    ExportGlb(export_glb::Args),
    /// Write the store as a 3D Tiles 1.1 tileset (CesiumJS), one GLB per cell.
    ExportTiles(export_tiles::Args),
    /// Render one frame of a store from a camera (headless GPU) to PNG.
    Render(render::Args),
    /// Timed fly-through over a store (headless GPU); writes a JSON report.
    Fly(fly::Args),
    /// Interactive window over a store: fly camera, overlays, texture modes (needs a display).
    View(view::Args),
}

/// Parses arguments, runs the command, prints errors as `error: ...` and maps them to exit codes.
pub fn run() -> ExitCode {
    let cli = Cli::parse();
    let _ = tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_env("CLIFFMAP_LOG")
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn")),
        )
        .with_writer(std::io::stderr)
        .try_init();
    if let Some(n) = cli.threads
        && let Err(e) = rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build_global()
    {
        eprintln!("error: cannot set up {n} threads: {e}");
        return ExitCode::from(2);
    }
    let result = match cli.command {
        Command::Demo(a) => demo::run(a),
        Command::Build(a) => build::run(a),
        Command::Reparam(a) => reparam::run(a),
        Command::Project(a) => project::run(a),
        Command::Stats(a) => stats::run(a),
        Command::Verify(a) => verify::run(a),
        Command::ExportObj(a) => export_obj::run(a),
        Command::ExportGlb(a) => export_glb::run(a),
        Command::ExportTiles(a) => export_tiles::run(a),
        Command::FitCamera(a) => fit_camera::run(a),
        Command::Register(a) => register::run(a),
        Command::Render(a) => render::run(a),
        Command::Fly(a) => fly::run(a),
        Command::View(a) => view::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Parses a byte size such as `8G`, `512M`, `1000000`.
pub(crate) fn parse_bytes(s: &str) -> Result<u64, String> {
    let s = s.trim();
    let (num, mul) = match s.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => {
            let mul: u64 = match c.to_ascii_uppercase() {
                'K' => 1 << 10,
                'M' => 1 << 20,
                'G' => 1 << 30,
                'T' => 1 << 40,
                _ => return Err(format!("unknown size suffix in {s:?} (use K, M, G or T)")),
            };
            (&s[..i], mul)
        }
        _ => (s, 1),
    };
    let n: f64 = num.parse().map_err(|_| format!("not a size: {s:?}"))?;
    if !(n.is_finite() && n > 0.0) {
        return Err(format!("size must be positive: {s:?}"));
    }
    Ok((n * mul as f64) as u64)
}

/// Parses `X,Y` into two finite numbers.
fn parse_pair(s: &str) -> Result<(f64, f64), String> {
    let v = parse_list(s, 2)?;
    Ok((v[0], v[1]))
}

/// Parses `n` comma-separated finite numbers.
fn parse_list(s: &str, n: usize) -> Result<Vec<f64>, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|p| {
            p.trim()
                .parse::<f64>()
                .map_err(|_| format!("not a number: {p:?} in {s:?}"))
        })
        .collect::<Result<_, _>>()?;
    if v.len() != n || v.iter().any(|x| !x.is_finite()) {
        return Err(format!(
            "expected {n} finite comma-separated numbers, got {s:?}"
        ));
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_sizes_and_pairs() {
        assert_eq!(parse_bytes("8G").unwrap(), 8 << 30);
        assert_eq!(parse_bytes("1000").unwrap(), 1000);
        assert!(parse_bytes("-1").is_err() && parse_bytes("3X").is_err());
        assert_eq!(
            parse_pair("445302.17, 7396769.45").unwrap(),
            (445302.17, 7396769.45)
        );
        assert!(parse_pair("1").is_err() && parse_pair("1,nan").is_err());
    }
}
