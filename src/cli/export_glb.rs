//! `cliffmap export-glb`: chosen cells as one GLB for Blender and generic glTF viewers.

use std::path::PathBuf;

use cliffmap::export::{CellSelection, GlbOptions, export_glb};

/// Flags of `cliffmap export-glb`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The store directory.
    store: PathBuf,
    /// Output GLB file.
    #[arg(long)]
    out: PathBuf,
    /// Quadtree level to export (0 = root; default: the finest).
    #[arg(long, conflicts_with = "max_error")]
    level: Option<u8>,
    /// Export the coarsest level whose every cell's error is at most this (metres).
    #[arg(long, allow_hyphen_values = true)]
    max_error: Option<f64>,
    /// Only cells meeting the rectangle "X0,Y0,X1,Y1" (world metres, the store's CRS).
    #[arg(long, allow_hyphen_values = true)]
    region: Option<String>,
    /// Lit materials: the normal maps in tangent space with NORMAL and TANGENT attributes,
    /// instead of unlit ones (KHR_materials_unlit) showing the texture as it is.
    #[arg(long)]
    lit: bool,
    /// Per-texel stretch and photo share as EXT_structural_metadata property textures.
    #[arg(long)]
    metadata: bool,
    /// Only warnings and errors.
    #[arg(long)]
    quiet: bool,
}

/// Runs `export-glb`.
pub fn run(a: Args) -> anyhow::Result<()> {
    if let Some(m) = a.max_error
        && !(m.is_finite() && m > 0.0)
    {
        anyhow::bail!("--max-error must be a positive number of metres, got {m}");
    }
    let region = match &a.region {
        None => None,
        Some(s) => {
            let v = super::parse_list(s, 4).map_err(|e| anyhow::anyhow!("--region: {e}"))?;
            if v[0] >= v[2] || v[1] >= v[3] {
                anyhow::bail!("--region: expected X0,Y0,X1,Y1 with X0 < X1 and Y0 < Y1, got {s}");
            }
            Some([v[0], v[1], v[2], v[3]])
        }
    };
    let r = export_glb(
        &a.store,
        &CellSelection {
            level: a.level,
            max_error: a.max_error,
            region,
        },
        &a.out,
        &GlbOptions {
            lit: a.lit,
            metadata: a.metadata,
        },
    )?;
    if !a.quiet {
        println!(
            "wrote {} ({} cells, {} triangles, textures: {} photo, {} reparam, {} ortho; {:.1} MB; origin {:.0}, {:.0}, {:.0})",
            a.out.display(),
            r.cells,
            r.triangles,
            r.textures[0],
            r.textures[1],
            r.textures[2],
            r.bytes as f64 / 1e6,
            r.origin.x,
            r.origin.y,
            r.origin.z
        );
    }
    Ok(())
}
