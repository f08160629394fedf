//! `cliffmap verify [--repair]`: damaged meshes, textures and manifests are found, named and
//! rebuilt to the exact original bytes from the recorded inputs.

mod cli_util;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use cli_util::{cliff_build_args, cliffmap, files_under, ok, s, write_cliff_dem};

fn build(dir: &Path) -> (PathBuf, PathBuf) {
    let dem = dir.join("dem.f32");
    write_cliff_dem(&dem);
    let store = dir.join("store");
    ok(&cliff_build_args(&dem, &store));
    ok(&["reparam", s(&store), "--quiet"]);
    (dem, store)
}

fn snapshot(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    // (.lock holds the pid of the last writer, not store content)
    files_under(dir)
        .into_iter()
        .filter(|p| p.file_name().is_some_and(|n| n != ".lock"))
        .map(|p| {
            (
                p.strip_prefix(dir).unwrap().display().to_string(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect()
}

fn manifest(store: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(store.join("manifest.json")).unwrap()).unwrap()
}

fn flip_byte(path: &Path, at: usize) {
    let mut b = std::fs::read(path).unwrap();
    let i = at.min(b.len() - 1);
    b[i] ^= 0x5a;
    std::fs::write(path, b).unwrap();
}

fn verify_fails_naming(store: &Path, names: &[&str]) {
    let o = cliffmap(&["verify", s(store)]);
    let out = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "verify should fail:\n{out}");
    assert!(!out.contains("panicked"), "{out}");
    for n in names {
        assert!(out.contains(n), "verify should name {n}:\n{out}");
    }
}

#[test]
fn damaged_cells_are_found_and_rebuilt_byte_identical() {
    let tmp = tempfile::tempdir().unwrap();
    let (_, store) = build(tmp.path());
    ok(&["verify", s(&store)]);
    let before = snapshot(&store);
    let m = manifest(&store);
    let cells = m["cells"].as_array().unwrap();
    let base_mesh = cells.last().unwrap()["files"]["mesh"]["path"]
        .as_str()
        .unwrap()
        .to_string();
    let truncated = cells[cells.len() - 2]["files"]["normal"]["path"]
        .as_str()
        .unwrap()
        .to_string();
    let reparam = cells
        .iter()
        .find(|c| c.get("reparam").is_some())
        .expect("the cliff makes some cell reparameterized");
    let reparam_tex = reparam["reparam"]["files"]["texture"]["path"]
        .as_str()
        .unwrap()
        .to_string();

    flip_byte(&store.join(&base_mesh), 100);
    flip_byte(&store.join(&reparam_tex), 200);
    let t = std::fs::read(store.join(&truncated)).unwrap();
    std::fs::write(store.join(&truncated), &t[..t.len() / 2]).unwrap();
    verify_fails_naming(
        &store,
        &[&base_mesh, &reparam_tex, &truncated, "3 problem(s)"],
    );

    let o = ok(&["verify", "--repair", s(&store)]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("repaired"), "{out}");
    ok(&["verify", s(&store)]);
    let after = snapshot(&store);
    assert_eq!(
        before.keys().collect::<Vec<_>>(),
        after.keys().collect::<Vec<_>>()
    );
    for (k, v) in &before {
        assert!(after[k] == *v, "{k} differs after the repair");
    }
}

#[test]
fn a_damaged_manifest_is_detected_and_the_base_rebuilt() {
    let tmp = tempfile::tempdir().unwrap();
    let (_, store) = build(tmp.path());
    // Change one digit of a recorded number: still valid JSON, so only the checksum sees it.
    let text = std::fs::read_to_string(store.join("manifest.json")).unwrap();
    let at = text.find("\"max_error\": ").unwrap() + "\"max_error\": ".len();
    let mut b = text.into_bytes();
    b[at] = if b[at] == b'1' { b'2' } else { b'1' };
    std::fs::write(store.join("manifest.json"), b).unwrap();
    verify_fails_naming(&store, &["manifest.json", "checksum mismatch"]);
    // Readers refuse it too, naming the file.
    let o = cliffmap(&["stats", s(&store)]);
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("manifest.json"));
    let o = ok(&["verify", "--repair", s(&store)]);
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("cliffmap reparam"),
        "the repair must say what to rerun"
    );
    ok(&["verify", s(&store)]);
    assert!(store.join("manifest.json.damaged").is_file());
}

#[test]
fn a_repair_without_the_inputs_says_which_are_missing() {
    let tmp = tempfile::tempdir().unwrap();
    let (dem, store) = build(tmp.path());
    let m = manifest(&store);
    let mesh = m["cells"][0]["files"]["mesh"]["path"]
        .as_str()
        .unwrap()
        .to_string();
    flip_byte(&store.join(&mesh), 40);
    std::fs::rename(&dem, tmp.path().join("moved.f32")).unwrap();
    let o = cliffmap(&["verify", "--repair", s(&store)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("missing") && err.contains("dem.f32"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn the_recipe_is_versioned_data_and_an_older_command_line_recipe_still_repairs() {
    let tmp = tempfile::tempdir().unwrap();
    let (dem, store) = build(tmp.path());
    let recipe: serde_json::Value =
        serde_json::from_slice(&std::fs::read(store.join("recipe.json")).unwrap()).unwrap();
    assert_eq!(recipe["recipe_version"], 1, "{recipe}");
    let recorded_dem = PathBuf::from(recipe["dem"].as_str().unwrap());
    assert!(recorded_dem.is_absolute(), "{recipe}");
    assert_eq!(
        recorded_dem.canonicalize().unwrap(),
        dem.canonicalize().unwrap()
    );
    let before = snapshot(&store);
    // The form stores built before the recipe was data have: the command line.
    let mut argv = vec!["cliffmap".to_string()];
    argv.extend(cliff_build_args(&dem, &store).iter().map(|a| a.to_string()));
    let old = serde_json::json!({"cwd": tmp.path(), "argv": argv});
    std::fs::write(store.join("recipe.json"), old.to_string()).unwrap();
    let mesh = manifest(&store)["cells"][0]["files"]["mesh"]["path"]
        .as_str()
        .unwrap()
        .to_string();
    flip_byte(&store.join(&mesh), 40);
    ok(&["verify", "--repair", s(&store)]);
    ok(&["verify", s(&store)]);
    let after = snapshot(&store);
    assert_eq!(
        before[&mesh], after[&mesh],
        "the mesh is rebuilt byte for byte"
    );
    // A key the recipe format does not know is refused, naming the file and the key.
    let mut bad = recipe.clone();
    bad["cell_intervls"] = serde_json::json!(32);
    std::fs::write(store.join("recipe.json"), bad.to_string()).unwrap();
    flip_byte(&store.join(&mesh), 40);
    let o = cliffmap(&["verify", "--repair", s(&store)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(
        err.contains("recipe.json") && err.contains("cell_intervls"),
        "{err}"
    );
}

#[test]
fn not_a_store_is_a_clear_error() {
    let tmp = tempfile::tempdir().unwrap();
    let o = cliffmap(&["verify", s(&tmp.path().join("nothing"))]);
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("nothing"));
    let o = cliffmap(&["verify", s(tmp.path())]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        !o.status.success() && out.contains("manifest.json"),
        "{out}"
    );
}

/// A store written with non-default PNG compression is repaired with the same compression
/// (the build's recipe and the reparam settings record it), byte for byte; a build resumed
/// with another compression is refused as "other options".
#[test]
fn a_repair_keeps_the_recorded_png_compression() {
    let tmp = tempfile::tempdir().unwrap();
    let dem = tmp.path().join("dem.f32");
    write_cliff_dem(&dem);
    let store = tmp.path().join("store");
    let mut args = cliff_build_args(&dem, &store);
    args.extend(["--png-compression", "balanced"]);
    ok(&args);
    ok(&["reparam", s(&store), "--quiet", "--png-compression", "best"]);
    let before = snapshot(&store);
    let m = manifest(&store);
    assert_eq!(m["reparam"]["png_compression"], "best");
    let cells = m["cells"].as_array().unwrap();
    let base_tex = cells[0]["files"]["texture"]["path"]
        .as_str()
        .unwrap()
        .to_string();
    let reparam_tex = cells
        .iter()
        .find_map(|c| c.get("reparam"))
        .expect("some cell is reparameterized")["files"]["texture"]["path"]
        .as_str()
        .unwrap()
        .to_string();
    flip_byte(&store.join(&base_tex), 60);
    flip_byte(&store.join(&reparam_tex), 60);
    ok(&["verify", "--repair", s(&store)]);
    let after = snapshot(&store);
    for (k, v) in &before {
        assert!(after.get(k) == Some(v), "{k} differs after the repair");
    }

    let mut other = cliff_build_args(&dem, &store);
    other.extend(["--png-compression", "fast"]);
    let o = cliffmap(&other);
    assert!(
        !o.status.success(),
        "a resume with another compression must be refused"
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("other inputs or options"));
}
