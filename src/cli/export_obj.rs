//! `cliffmap export-obj`: one cell as Wavefront OBJ.

use std::path::PathBuf;

use cliffmap::fsutil::write_atomic;
use cliffmap::store::{Store, obj_text};

/// Flags of `cliffmap export-obj`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The store directory.
    store: PathBuf,
    /// Cell id, "LEVEL-X-Y" (see stats.json).
    #[arg(long)]
    cell: String,
    /// Write georeferenced world coordinates instead of cell-local ones.
    #[arg(long)]
    world: bool,
    /// Output OBJ file.
    #[arg(long)]
    out: PathBuf,
}

/// Runs `export-obj`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let store = Store::open(&a.store)?;
    let rec = store.cell(&a.cell)?;
    let mesh = store.read_active_mesh(rec)?;
    write_atomic(&a.out, obj_text(rec, &mesh, a.world).as_bytes())?;
    Ok(())
}
