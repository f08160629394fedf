//! The layering of `src/` stays as docs/architecture.md documents it: a library module may
//! import only modules of a lower layer (the "Layers" table), and no file or subfolder of a
//! folder imports a sibling that imports it back (directly or through other siblings).
//!
//! Imports are read from the source text: every `crate::NAME` path outside comments and
//! outside the trailing `#[cfg(test)] mod tests` (tests may use anything), and within a
//! folder every `super::NAME` / `crate::FOLDER::NAME` naming a sibling file or subfolder.

mod cli_util;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The module → layer map of the "Layers" table of docs/architecture.md: rows
/// `| N | `a`, `b` | … |` after the heading `## Layers`.
fn documented_layers() -> BTreeMap<String, u32> {
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/architecture.md"))
            .expect("docs/architecture.md");
    let section = doc
        .split("\n## Layers")
        .nth(1)
        .expect("docs/architecture.md has a \"## Layers\" section");
    let section = section.split("\n## ").next().unwrap_or(section);
    let mut layers = BTreeMap::new();
    for line in section.lines() {
        let cols: Vec<&str> = line.split('|').map(str::trim).collect();
        if cols.len() < 4 {
            continue;
        }
        let Ok(layer) = cols[1].parse::<u32>() else {
            continue;
        };
        for name in cols[2].split(',') {
            let name = name.trim().trim_matches('`');
            assert!(
                !name.is_empty(),
                "empty module name in layer {layer}: {line}"
            );
            let before = layers.insert(name.to_string(), layer);
            assert!(
                before.is_none(),
                "module `{name}` listed twice in the Layers table"
            );
        }
    }
    assert!(
        layers.len() > 10,
        "the Layers table lists only {} modules",
        layers.len()
    );
    layers
}

/// Every `.rs` file under `dir`, sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = cli_util::files_under(dir)
        .into_iter()
        .filter(|p| p.extension().is_some_and(|x| x == "rs"))
        .collect();
    out.sort();
    out
}

/// The code of a file without its comments and without its trailing test module.
fn code_of(path: &Path) -> String {
    let text = std::fs::read_to_string(path).expect("read source");
    let text = match text.find("#[cfg(test)]\nmod tests") {
        Some(i) => &text[..i],
        None => &text[..],
    };
    text.lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .map(|l| match l.find(" // ") {
            Some(i) => &l[..i],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The identifiers that follow `prefix` in `code` (`crate::{a, b}` gives both).
fn names_after(code: &str, prefix: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect()
    };
    for (i, _) in code.match_indices(prefix) {
        // `crate::x` but not `othercrate::x`
        if i > 0
            && code[..i]
                .chars()
                .last()
                .is_some_and(|c| c.is_ascii_alphanumeric() || c == '_')
        {
            continue;
        }
        let rest = &code[i + prefix.len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            for item in group[..end].split(',') {
                let n = ident(item.trim());
                if !n.is_empty() {
                    out.insert(n);
                }
            }
        } else {
            let n = ident(rest);
            if !n.is_empty() {
                out.insert(n);
            }
        }
    }
    out
}

/// The top-level module a file of `src/` belongs to (`photo` for `src/photo/blend.rs`).
fn top_module(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).expect("under src");
    let first = rel.components().next().expect("a component");
    first
        .as_os_str()
        .to_string_lossy()
        .trim_end_matches(".rs")
        .to_string()
}

#[test]
fn modules_import_only_lower_layers() {
    let layers = documented_layers();
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let lib = std::fs::read_to_string(src.join("lib.rs")).expect("lib.rs");
    let declared: BTreeSet<String> = lib
        .lines()
        .filter_map(|l| {
            let l = l.trim();
            let l = l.strip_prefix("pub ").unwrap_or(l);
            l.strip_prefix("mod ")
                .map(|m| m.trim_end_matches(';').to_string())
        })
        .filter(|m| m != "tiffgen")
        .collect();
    let missing: Vec<_> = declared
        .iter()
        .filter(|m| !layers.contains_key(*m))
        .collect();
    assert!(
        missing.is_empty(),
        "modules of lib.rs missing from the Layers table of docs/architecture.md: {missing:?}"
    );
    let mut violations = Vec::new();
    for file in rust_files(&src) {
        let top = top_module(&src, &file);
        let Some(&own) = layers.get(&top) else {
            continue; // lib.rs, main.rs and the CLI (the binary, above every layer)
        };
        for used in names_after(&code_of(&file), "crate::") {
            if used == top {
                continue;
            }
            match layers.get(&used) {
                Some(&l) if l < own => {}
                Some(&l) => violations.push(format!(
                    "{} (`{top}`, layer {own}) imports `{used}` (layer {l})",
                    file.strip_prefix(&src).unwrap_or(&file).display()
                )),
                None => {}
            }
        }
    }
    assert!(
        violations.is_empty(),
        "imports that point up or sideways (docs/architecture.md, Layers):\n{}",
        violations.join("\n")
    );
}

/// The children of folder `dir` (file stems and subfolder names; `mod.rs` excluded).
fn children(dir: &Path) -> BTreeSet<String> {
    std::fs::read_dir(dir)
        .expect("read folder")
        .filter_map(|e| {
            let p = e.ok()?.path();
            let s = p.file_stem()?.to_string_lossy().to_string();
            (s != "mod" && (p.is_dir() || p.extension().is_some_and(|x| x == "rs"))).then_some(s)
        })
        .collect()
}

/// `src/a/b` as the module path `a::b`.
fn module_path(src: &Path, dir: &Path) -> String {
    dir.strip_prefix(src)
        .expect("under src")
        .components()
        .map(|c| c.as_os_str().to_string_lossy().to_string())
        .collect::<Vec<_>>()
        .join("::")
}

#[test]
fn no_file_or_folder_imports_a_sibling_that_imports_it_back() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    // folder -> (child -> siblings it imports): a child is a file or a subfolder (all the
    // files under it), an import `super::NAME` from a file directly in the folder or
    // `crate::FOLDER::NAME` from any file under it.
    let mut graph: BTreeMap<PathBuf, BTreeMap<String, BTreeSet<String>>> = BTreeMap::new();
    for file in rust_files(&src) {
        let code = code_of(&file);
        let mut dir = file.parent().expect("a folder").to_path_buf();
        let mut child = file
            .file_stem()
            .unwrap_or_default()
            .to_string_lossy()
            .to_string();
        let direct = child != "mod";
        loop {
            let siblings = children(&dir);
            let path = module_path(&src, &dir);
            let mut used = if path.is_empty() {
                names_after(&code, "crate::")
            } else {
                names_after(&code, &format!("crate::{path}::"))
            };
            if direct && dir == file.parent().expect("a folder") {
                used.extend(names_after(&code, "super::"));
            }
            if child != "mod" && child != "lib" && child != "main" {
                let deps: BTreeSet<String> = used
                    .into_iter()
                    .filter(|u| *u != child && siblings.contains(u))
                    .collect();
                graph
                    .entry(dir.clone())
                    .or_default()
                    .entry(child.clone())
                    .or_default()
                    .extend(deps);
            }
            if dir == src {
                break;
            }
            child = dir
                .file_name()
                .unwrap_or_default()
                .to_string_lossy()
                .to_string();
            dir = dir.parent().expect("under src").to_path_buf();
        }
    }
    let mut cycles = Vec::new();
    for (dir, nodes) in &graph {
        for start in nodes.keys() {
            // depth-first search for a path back to `start`
            let mut stack: Vec<Vec<String>> = vec![vec![start.clone()]];
            let mut seen = BTreeSet::new();
            while let Some(path) = stack.pop() {
                let last = path.last().expect("non-empty");
                for next in nodes.get(last).into_iter().flatten() {
                    if next == start {
                        let mut c = path.clone();
                        c.push(start.clone());
                        cycles.push(format!(
                            "{}: {}",
                            dir.strip_prefix(&src).unwrap_or(dir).display(),
                            c.join(" -> ")
                        ));
                    } else if seen.insert(next.clone()) {
                        let mut p = path.clone();
                        p.push(next.clone());
                        stack.push(p);
                    }
                }
            }
        }
    }
    assert!(
        cycles.is_empty(),
        "import cycles between files or folders:\n{}",
        cycles.join("\n")
    );
}

#[test]
fn the_reader_finds_imports_it_must_see() {
    let code = "use crate::{store::Store, cells};\nlet x = crate::photo::f();\nmycrate::no();";
    let got = names_after(code, "crate::");
    assert_eq!(
        got.into_iter().collect::<Vec<_>>(),
        ["cells", "photo", "store"]
    );
}
