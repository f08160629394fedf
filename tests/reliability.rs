//! Concurrent writers and full disks: a second writer is refused with a clear message; a
//! build, reparam or project that runs out of space fails naming the file, leaves no temporary
//! file and no half-updated store, and (for a build) resumes to the same store.
//!
//! The full-disk tests mount a small tmpfs, which needs root (as in CI, see .ci/run).

mod cli_util;

use std::path::{Path, PathBuf};
use std::process::Command;

use cli_util::{cliff_build_args, cliffmap, files_under, ok, s, write_cliff_dem};

/// A tmpfs of `kib` KiB mounted on a fresh directory (unmounted on drop), or where it
/// cannot be mounted (not root), a plain directory plus the environment that makes
/// cliffmap's own writes fail with ENOSPC after the same number of bytes
/// (`CLIFFMAP_TEST_DISK_BYTES`, the fault injection of `fsutil::write_atomic`).
struct SmallFs {
    dir: tempfile::TempDir,
    mounted: bool,
    kib: u64,
}

impl SmallFs {
    fn new(kib: u64) -> SmallFs {
        let dir = tempfile::tempdir().unwrap();
        let mounted = Command::new("mount")
            .args([
                "-t",
                "tmpfs",
                "-o",
                &format!("size={kib}k"),
                "tmpfs",
                s(dir.path()),
            ])
            .stderr(std::process::Stdio::null())
            .status()
            .is_ok_and(|st| st.success());
        if !mounted {
            eprintln!(
                "cannot mount a tmpfs (not root?): using cliffmap's injected ENOSPC after {kib} KiB instead"
            );
        }
        SmallFs { dir, mounted, kib }
    }
    fn path(&self) -> PathBuf {
        self.dir.path().to_path_buf()
    }
    /// Runs cliffmap on this file system; `already` = KiB already on it (injection only).
    fn cliffmap(&self, args: &[&str], already_kib: u64) -> std::process::Output {
        let mut c = Command::new(env!("CARGO_BIN_EXE_cliffmap"));
        c.args(args);
        if !self.mounted {
            c.env(
                "CLIFFMAP_TEST_DISK_BYTES",
                (self.kib.saturating_sub(already_kib) * 1024).to_string(),
            );
        }
        c.output().expect("cannot start cliffmap")
    }
}

impl Drop for SmallFs {
    fn drop(&mut self) {
        if self.mounted {
            let _ = Command::new("umount").arg(self.dir.path()).status();
        }
    }
}

fn copy_dir(from: &Path, to: &Path) {
    for f in files_under(from) {
        let rel = f.strip_prefix(from).unwrap();
        std::fs::create_dir_all(to.join(rel).parent().unwrap()).unwrap();
        std::fs::copy(&f, to.join(rel)).unwrap();
    }
}

#[test]
fn a_second_writer_is_refused_while_the_first_holds_the_store() {
    let tmp = tempfile::tempdir().unwrap();
    let dem = tmp.path().join("dem.f32");
    write_cliff_dem(&dem);
    let store = tmp.path().join("store");
    ok(&cliff_build_args(&dem, &store));
    // Hold the lock as another writer would (a separate open file description).
    let f = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(store.join(".lock"))
        .unwrap();
    f.try_lock().unwrap();
    for args in [
        vec!["reparam", s(&store), "--quiet"],
        cliff_build_args(&dem, &store),
        vec!["verify", "--repair", s(&store)],
    ] {
        let o = cliffmap(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} should be refused");
        assert!(
            err.contains("another cliffmap process is writing this store") && err.contains("store"),
            "{args:?}: {err}"
        );
    }
    // Readers keep working.
    ok(&["verify", s(&store)]);
    ok(&["stats", s(&store)]);
    drop(f);
    ok(&["reparam", s(&store), "--quiet"]);
}

#[test]
fn a_build_that_fills_the_disk_fails_cleanly_and_resumes() {
    let tmp = tempfile::tempdir().unwrap();
    let dem = tmp.path().join("dem.f32");
    write_cliff_dem(&dem);
    let fs = SmallFs::new(400);
    let store = fs.path().join("store");
    let o = fs.cliffmap(&cliff_build_args(&dem, &store), 0);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "the build should run out of space");
    assert!(
        err.contains("No space left on device") && err.contains(s(&store)),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    let files = files_under(&store);
    assert!(
        !files.iter().any(|p| p.to_string_lossy().ends_with(".tmp")),
        "temporary files left: {files:?}"
    );
    assert!(
        !store.join("manifest.json").exists(),
        "no manifest for an unfinished build"
    );
    // Resume on a disk with space: the same store as a build that never failed.
    let resumed = tmp.path().join("resumed");
    copy_dir(&store, &resumed);
    ok(&cliff_build_args(&dem, &resumed));
    let fresh = tmp.path().join("fresh");
    ok(&cliff_build_args(&dem, &fresh));
    ok(&["verify", s(&resumed)]);
    let (a, b) = (files_under(&resumed), files_under(&fresh));
    let rel = |v: &[PathBuf], root: &Path| {
        v.iter()
            .map(|p| p.strip_prefix(root).unwrap().to_path_buf())
            .collect::<Vec<_>>()
    };
    let names = |v: Vec<PathBuf>| {
        v.into_iter()
            .filter(|p| !p.ends_with(".lock") && !p.ends_with("recipe.json"))
            .collect::<Vec<_>>()
    };
    let (ra, rb) = (names(rel(&a, &resumed)), names(rel(&b, &fresh)));
    assert_eq!(ra, rb);
    for r in &ra {
        assert!(
            std::fs::read(resumed.join(r)).unwrap() == std::fs::read(fresh.join(r)).unwrap(),
            "{} differs",
            r.display()
        );
    }
}

#[test]
fn a_reparam_that_fills_the_disk_leaves_the_store_as_it_was() {
    let tmp = tempfile::tempdir().unwrap();
    let dem = tmp.path().join("dem.f32");
    write_cliff_dem(&dem);
    let built = tmp.path().join("store");
    ok(&cliff_build_args(&dem, &built));
    let size: u64 = files_under(&built)
        .iter()
        .map(|p| std::fs::metadata(p).unwrap().len().div_ceil(4096) * 4096)
        .sum();
    let fs = SmallFs::new(size / 1024 + 200);
    let store = fs.path().join("store");
    copy_dir(&built, &store);
    let manifest_before = std::fs::read(store.join("manifest.json")).unwrap();
    let o = fs.cliffmap(&["reparam", s(&store), "--quiet"], size / 1024);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "reparam should run out of space");
    assert!(err.contains("No space left on device"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(
        std::fs::read(store.join("manifest.json")).unwrap(),
        manifest_before,
        "the manifest must be untouched"
    );
    assert!(
        !files_under(&store)
            .iter()
            .any(|p| p.to_string_lossy().ends_with(".tmp"))
    );
    ok(&["verify", s(&store)]);
}

#[test]
fn a_project_that_fills_the_disk_leaves_the_store_as_it_was() {
    use cliffmap::pipeline::{BuildInputs, BuildOptions, build_store};
    let tmp = tempfile::tempdir().unwrap();
    let scene = cliffmap::demo_scene::DemoScene {
        samples: 129,
        spacing: 4.0,
        ..cliffmap::demo_scene::DemoScene::default()
    };
    let (dem, ortho) = scene.generate().unwrap();
    let built = tmp.path().join("store");
    build_store(
        &BuildInputs {
            dem: &dem,
            ortho: Some(&ortho),
            dem_source: "t".into(),
            ortho_source: Some("t".into()),
            fingerprint: "project-enospc".into(),
        },
        &BuildOptions {
            cell_intervals: 32,
            cell_texels: 64,
            force: true,
            ..BuildOptions::default()
        },
        &built,
    )
    .unwrap();
    let list = scene
        .write_demo_photos(
            &dem,
            &tmp.path().join("photos"),
            &cliffmap::demo_scene::DemoPhotoOptions {
                width: 320,
                height: 240,
                supersample: 1,
            },
        )
        .unwrap();
    let size: u64 = files_under(&built)
        .iter()
        .map(|p| std::fs::metadata(p).unwrap().len().div_ceil(4096) * 4096)
        .sum();
    let fs = SmallFs::new(size / 1024 + 64);
    let store = fs.path().join("store");
    copy_dir(&built, &store);
    let manifest_before = std::fs::read(store.join("manifest.json")).unwrap();
    let o = fs.cliffmap(
        &["project", s(&store), "--photos", s(&list), "--quiet"],
        size / 1024,
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "project should run out of space");
    assert!(err.contains("No space left on device"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(
        std::fs::read(store.join("manifest.json")).unwrap(),
        manifest_before,
        "the manifest must be untouched"
    );
    assert!(
        !files_under(&store)
            .iter()
            .any(|p| p.to_string_lossy().ends_with(".tmp"))
    );
    ok(&["verify", s(&store)]);
    // Moved to a disk with room, the left store takes the same command.
    let again = tmp.path().join("again");
    copy_dir(&store, &again);
    ok(&["project", s(&again), "--photos", s(&list), "--quiet"]);
    ok(&["verify", s(&again)]);
}
