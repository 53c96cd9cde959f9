#![allow(clippy::unwrap_used, clippy::expect_used, clippy::disallowed_methods)]
//! The dependency graph in `ARCHITECTURE.md` is the workspace's: every member's normal
//! dependencies on other workspace crates, read from its `Cargo.toml`, must be the ones the
//! page lists, and no crate may depend on one listed after it (the graph points one way).
//! Inside every crate, no modules import each other, directly or around a circle.

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

/// A crate's modules (`a::b` for `src/a/b.rs` or `src/a/b/mod.rs`; the crate root is left out:
/// it only declares and re-exports) and their source.
fn modules(src: &Path) -> BTreeMap<String, String> {
    fn walk(dir: &Path, src: &Path, out: &mut BTreeMap<String, String>) {
        for entry in std::fs::read_dir(dir).expect("a readable source folder") {
            let path = entry.expect("a directory entry").path();
            if path.is_dir() {
                walk(&path, src, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let rel = path
                    .strip_prefix(src)
                    .expect("below src")
                    .with_extension("");
                let mut parts: Vec<String> = rel
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect();
                if matches!(
                    parts.last().map(String::as_str),
                    Some("mod" | "lib" | "main")
                ) {
                    parts.pop();
                }
                if !parts.is_empty() {
                    let text = std::fs::read_to_string(&path).expect("a readable source file");
                    out.insert(parts.join("::"), text);
                }
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(src, src, &mut out);
    out
}

/// The code of a source file that its module's imports are read from: comments and the unit
/// tests (`#[cfg(test)] mod tests`, at the end by the workspace's convention) left out.
fn code_of(text: &str) -> String {
    let text = text
        .find("#[cfg(test)]\nmod tests")
        .or_else(|| text.find("#[cfg(test)]\n#[allow"))
        .map_or(text, |at| &text[..at]);
    text.lines()
        .map(|line| line.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The module of `modules` a path `a::b::Item` names: its longest prefix that is a module.
fn module_named<'a>(modules: &'a BTreeMap<String, String>, path: &str) -> Option<&'a str> {
    let parts: Vec<&str> = path.split("::").collect();
    (1..=parts.len())
        .rev()
        .map(|k| parts[..k].join("::"))
        .find_map(|name| modules.get_key_value(&name).map(|(k, _)| k.as_str()))
}

/// Every `crate::...` and `super::...` path of a module's code, as a path from the crate
/// root (`use crate::{a, b::c}` lists are expanded one level).
fn paths_of(module: &str, code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let parent: Vec<&str> = module.split("::").collect();
    let parent = parent[..parent.len() - 1].join("::");
    let words = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':')
            .collect()
    };
    for (prefix, base) in [("crate::", String::new()), ("super::", parent)] {
        for (at, _) in code.match_indices(prefix) {
            let rest = &code[at + prefix.len()..];
            let join = |p: String| {
                if base.is_empty() {
                    p
                } else {
                    format!("{base}::{p}")
                }
            };
            if let Some(list) = rest.strip_prefix('{') {
                let list = &list[..list.find('}').unwrap_or(list.len())];
                out.extend(list.split(',').map(|item| join(words(item.trim()))));
            } else {
                out.push(join(words(rest)));
            }
        }
    }
    out
}

/// The circles of a crate's module graph (strongly connected sets of two or more modules).
fn circles(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    // Kosaraju: finishing order on the graph, then components on the reversed graph.
    fn visit(
        v: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        seen: &mut BTreeSet<String>,
        order: &mut Vec<String>,
    ) {
        if !seen.insert(v.to_string()) {
            return;
        }
        for w in &graph[v] {
            visit(w, graph, seen, order);
        }
        order.push(v.to_string());
    }
    let mut seen = BTreeSet::new();
    let mut order = Vec::new();
    for v in graph.keys() {
        visit(v, graph, &mut seen, &mut order);
    }
    let mut reversed: BTreeMap<String, BTreeSet<String>> =
        graph.keys().map(|k| (k.clone(), BTreeSet::new())).collect();
    for (v, ws) in graph {
        for w in ws {
            reversed.get_mut(w).expect("a module").insert(v.clone());
        }
    }
    let mut seen = BTreeSet::new();
    let mut out = Vec::new();
    for v in order.iter().rev() {
        let mut component = Vec::new();
        visit(v, &reversed, &mut seen, &mut component);
        if component.len() > 1 {
            component.sort();
            out.push(component);
        }
    }
    out
}

/// A crate's module graph: an arrow from a module to every other module its code names.
fn module_graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let modules = modules(src);
    modules
        .iter()
        .map(|(name, text)| {
            let targets = paths_of(name, &code_of(text))
                .iter()
                .filter_map(|p| module_named(&modules, p))
                .filter(|t| *t != name && !name.starts_with(&format!("{t}::")))
                .map(str::to_string)
                .collect();
            (name.clone(), targets)
        })
        .collect()
}

#[test]
fn no_crate_has_an_import_circle_among_its_modules() {
    let root = repo_root();
    let mut found = Vec::new();
    for manifest in manifests(&root) {
        let src = manifest.parent().expect("a crate folder").join("src");
        if !src.is_dir() {
            continue;
        }
        for circle in circles(&module_graph(&src)) {
            let krate = src.strip_prefix(&root).unwrap_or(&src);
            found.push(format!("{}: {}", krate.display(), circle.join(" <-> ")));
        }
    }
    assert!(
        found.is_empty(),
        "modules that import each other (directly or around a circle):\n{}",
        found.join("\n")
    );
}

#[test]
fn the_circle_finder_finds_a_circle_and_no_other() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let src = dir.path();
    std::fs::create_dir_all(src.join("b")).unwrap();
    std::fs::write(src.join("lib.rs"), "mod a;\nmod b;\nmod c;\n").unwrap();
    std::fs::write(src.join("a.rs"), "use crate::b::inner::X;\n").unwrap();
    std::fs::write(src.join("b/mod.rs"), "pub mod inner;\n").unwrap();
    std::fs::write(src.join("b/inner.rs"), "use crate::{c::Y, a};\n").unwrap();
    std::fs::write(
        src.join("c.rs"),
        "// crate::a::Z in a comment does not count\n#[cfg(test)]\nmod tests {\n    use crate::a;\n}\n",
    )
    .unwrap();
    let graph = module_graph(src);
    assert_eq!(
        circles(&graph),
        vec![vec!["a".to_string(), "b::inner".to_string()]]
    );
    assert!(graph["c"].is_empty());
}
