#![allow(clippy::unwrap_used, clippy::expect_used, clippy::disallowed_methods)]
//! The dependency graph in `ARCHITECTURE.md` is the workspace's: every member's normal
//! dependencies on other workspace crates, read from its `Cargo.toml`, must be the ones the
//! page lists, and no crate may depend on one listed after it (the graph points one way).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

type Graph = BTreeMap<String, BTreeSet<String>>;

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The workspace members' manifests: `crates/*/Cargo.toml` and `examples/Cargo.toml`.
fn manifests(root: &Path) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(root.join("crates"))
        .expect("crates/ is readable")
        .map(|e| e.expect("a directory entry").path().join("Cargo.toml"))
        .filter(|p| p.is_file())
        .collect();
    let examples = root.join("examples/Cargo.toml");
    if examples.is_file() {
        out.push(examples);
    }
    out.sort();
    out
}

/// The package name and the workspace crates among its normal dependencies (`[dependencies]`
/// and target-specific `[target.'..'.dependencies]`).
fn read_manifest(path: &Path) -> (String, BTreeSet<String>) {
    let text = std::fs::read_to_string(path).expect("a readable manifest");
    let mut name = None;
    let mut section = String::new();
    let mut deps = BTreeSet::new();
    for line in text.lines().map(str::trim) {
        if line.starts_with('[') {
            section = line.to_string();
            continue;
        }
        if section == "[package]" && line.starts_with("name") {
            name = line.split('"').nth(1).map(str::to_string);
        }
        let normal = section == "[dependencies]"
            || (section.starts_with("[target.") && section.ends_with(".dependencies]"));
        if normal && line.starts_with("omnimvs-") {
            let dep: String = line
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '-' || *c == '_')
                .collect();
            deps.insert(dep);
        }
    }
    (
        name.unwrap_or_else(|| panic!("{}: no [package] name", path.display())),
        deps,
    )
}

/// The graph block of `ARCHITECTURE.md`, in its order.
fn documented(root: &Path) -> Vec<(String, BTreeSet<String>)> {
    let text = std::fs::read_to_string(root.join("ARCHITECTURE.md")).expect("ARCHITECTURE.md");
    let start = text
        .find("<!-- dependency-graph:begin -->")
        .expect("ARCHITECTURE.md has a dependency-graph:begin marker");
    let end = text
        .find("<!-- dependency-graph:end -->")
        .expect("ARCHITECTURE.md has a dependency-graph:end marker");
    text[start..end]
        .lines()
        .skip(1) // the marker itself
        .filter(|line| line.starts_with("omnimvs-"))
        .filter_map(|line| line.split_once("->"))
        .map(|(krate, deps)| {
            let deps = deps
                .split(',')
                .map(str::trim)
                .filter(|d| !d.is_empty())
                .map(str::to_string)
                .collect();
            (krate.trim().to_string(), deps)
        })
        .collect()
}

#[test]
fn the_documented_graph_is_the_workspace_graph() {
    let root = repo_root();
    let actual: Graph = manifests(&root).iter().map(|p| read_manifest(p)).collect();
    let listed = documented(&root);
    let documented: Graph = listed.iter().cloned().collect();
    let mut expected_block = String::new();
    for (krate, deps) in &actual {
        let deps: Vec<&str> = deps.iter().map(String::as_str).collect();
        expected_block.push_str(&format!("{krate} -> {}\n", deps.join(", ")));
    }
    assert_eq!(
        documented, actual,
        "ARCHITECTURE.md's dependency graph differs from the manifests; the manifests say:\n{expected_block}"
    );
}

#[test]
fn the_graph_points_one_way() {
    let listed = documented(&repo_root());
    let position: BTreeMap<&str, usize> = listed
        .iter()
        .enumerate()
        .map(|(i, (k, _))| (k.as_str(), i))
        .collect();
    for (i, (krate, deps)) in listed.iter().enumerate() {
        for dep in deps {
            let j = position
                .get(dep.as_str())
                .unwrap_or_else(|| panic!("{krate} depends on {dep}, which is not listed"));
            assert!(
                *j < i,
                "{krate} depends on {dep}, listed after it: list the crates lowest first"
            );
        }
    }
}

#[test]
fn the_manifest_reader_sees_target_specific_dependencies() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let path = dir.path().join("Cargo.toml");
    std::fs::write(
        &path,
        "[package]\nname = \"a\"\n\n[dependencies]\nomnimvs-camera.workspace = true\nserde = \"1\"\n\n\
         [target.'cfg(unix)'.dependencies]\nomnimvs-sweep = { path = \"x\" }\n\n\
         [dev-dependencies]\nomnimvs-data.workspace = true\n",
    )
    .expect("write a manifest");
    let (name, deps) = read_manifest(&path);
    assert_eq!(name, "a");
    assert_eq!(
        deps.into_iter().collect::<Vec<_>>(),
        vec!["omnimvs-camera".to_string(), "omnimvs-sweep".to_string()]
    );
}
