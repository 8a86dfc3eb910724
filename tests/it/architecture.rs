//! The boundaries ARCHITECTURE.md states, held by the build: the crates' dependencies (read
//! from `cargo metadata`), the modules inside each crate, the diagnostic codes, the numbers,
//! and the docs.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use serde_json::Value;

/// One workspace crate: its name, its folder, and its dependencies by kind.
#[derive(Debug)]
struct Krate {
    name: String,
    dir: PathBuf,
    /// Normal (not dev, not build) dependencies, workspace and external.
    normal: Vec<String>,
}

/// The workspace's crates, as cargo sees them.
fn workspace() -> BTreeMap<String, Krate> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = std::process::Command::new(cargo)
        .args([
            "metadata",
            "--format-version",
            "1",
            "--offline",
            "--no-deps",
        ])
        .current_dir(crate::common::workspace())
        .output()
        .expect("cargo metadata runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let meta: Value = serde_json::from_slice(&out.stdout).expect("cargo metadata is JSON");
    let mut crates = BTreeMap::new();
    for p in meta["packages"].as_array().expect("packages") {
        let name = p["name"].as_str().expect("a name").to_string();
        let manifest = PathBuf::from(p["manifest_path"].as_str().expect("a manifest"));
        let normal = (p["dependencies"].as_array().expect("dependencies").iter())
            .filter(|d| d["kind"].is_null())
            .map(|d| d["name"].as_str().expect("a dependency's name").to_string())
            .collect();
        let dir = manifest.parent().expect("a folder").to_path_buf();
        crates.insert(name.clone(), Krate { name, dir, normal });
    }
    assert!(crates.len() >= 16, "{:?}", crates.keys());
    crates
}

/// Every crate `name` depends on, directly or through others (normal dependencies; external
/// crates are followed as far as the workspace knows them: their names are included).
fn closure(crates: &BTreeMap<String, Krate>, name: &str) -> BTreeSet<String> {
    let mut seen = BTreeSet::new();
    let mut todo = vec![name.to_string()];
    while let Some(n) = todo.pop() {
        for d in crates.get(&n).map_or(&[][..], |k| &k.normal[..]) {
            if seen.insert(d.clone()) {
                todo.push(d.clone());
            }
        }
    }
    seen
}

/// A crate's Rust sources under `src/` outside its tests: `(path, text)`, the text cut at
/// `#[cfg(test)] mod tests`, comments dropped.
fn sources(k: &Krate) -> Vec<(PathBuf, String)> {
    let mut files = Vec::new();
    let mut stack = vec![k.dir.join("src")];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                let text = std::fs::read_to_string(&p).expect("a readable source");
                let code = text.split("#[cfg(test)]\nmod tests").next().unwrap_or("");
                let code: Vec<&str> = code
                    .lines()
                    .map(|l| l.split("//").next().unwrap_or(""))
                    .collect();
                files.push((p, code.join("\n")));
            }
        }
    }
    files.sort();
    files
}

/// The crates that implement a backend: a `Drone` or a `Mocap` for the flight loop.
fn backend_crates(crates: &BTreeMap<String, Krate>) -> BTreeSet<String> {
    let backends: BTreeSet<String> = crates
        .values()
        .filter(|k| {
            sources(k).iter().any(|(_, code)| {
                ["impl Drone for", "impl Mocap for"]
                    .iter()
                    .any(|i| code.contains(i))
            })
        })
        .map(|k| k.name.clone())
        .collect();
    for known in ["dronecine-sim", "dronecine-ardrone", "dronecine-natnet"] {
        assert!(
            backends.contains(known),
            "{known} not found among {backends:?}"
        );
    }
    backends
}

#[test]
fn the_flight_loop_depends_on_no_backend_crate() {
    let crates = workspace();
    let backends = backend_crates(&crates);
    let deps = closure(&crates, "dronecine-flight");
    let found: Vec<&String> = deps.intersection(&backends).collect();
    assert!(
        found.is_empty(),
        "dronecine-flight reaches {found:?}: it sees the hardware through dronecine-backend's \
         traits only"
    );
    assert!(deps.contains("dronecine-backend"));
}

#[test]
fn the_grammar_knows_nothing_of_drones() {
    let crates = workspace();
    let deps = closure(&crates, "dronecine-grammar");
    let ours: BTreeSet<&String> = deps.iter().filter(|d| crates.contains_key(*d)).collect();
    let allowed = ["dronecine-diag", "dronecine-math"];
    assert!(
        ours.iter().all(|d| allowed.contains(&d.as_str())),
        "dronecine-grammar depends on {ours:?}; only {allowed:?} are below it"
    );
    for c in dronecine_grammar::PslCode::ALL {
        assert_eq!(
            c.code().namespace(),
            "psl",
            "{c}: each crate owns its codes"
        );
    }
}

#[test]
fn only_the_preview_crate_renders() {
    const RENDERERS: [&str; 4] = ["resvg", "usvg", "tiny-skia", "png"];
    let crates = workspace();
    let compiler = closure(&crates, "dronecine-compiler");
    for r in RENDERERS.iter().chain(&["dronecine-preview"]) {
        assert!(!compiler.contains(*r), "dronecine-compiler depends on {r}");
    }
    for k in crates.values() {
        let renders: Vec<&String> = (k.normal.iter())
            .filter(|d| RENDERERS.contains(&d.as_str()))
            .collect();
        assert!(
            renders.is_empty() || k.name == "dronecine-preview",
            "{} depends on {renders:?}: only dronecine-preview renders",
            k.name
        );
    }
}

/// The modules a crate's top-level module `from` names (`crate::x`, `use crate::{x, y}`).
fn names_of_modules(code: &str, modules: &BTreeSet<String>) -> BTreeSet<String> {
    let mut found = BTreeSet::new();
    for (i, _) in code.match_indices("crate::") {
        let rest = &code[i + "crate::".len()..];
        let names: Vec<&str> = match rest.strip_prefix('{') {
            Some(group) => group
                .split('}')
                .next()
                .unwrap_or("")
                .split(',')
                .map(|s| s.trim().split("::").next().unwrap_or(""))
                .collect(),
            None => vec![rest
                .split(|c: char| !(c.is_alphanumeric() || c == '_'))
                .next()
                .unwrap_or("")],
        };
        found.extend(
            names
                .into_iter()
                .filter(|n| modules.contains(*n))
                .map(String::from),
        );
    }
    found
}

/// A cycle in `graph`, if there is one: the modules along it.
fn a_cycle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        n: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(n.to_string(), 1);
        path.push(n.to_string());
        for m in graph.get(n).into_iter().flatten() {
            match state.get(m).copied().unwrap_or(0) {
                1 => {
                    let from = path.iter().position(|p| p == m).unwrap_or(0);
                    let mut cycle = path[from..].to_vec();
                    cycle.push(m.clone());
                    return Some(cycle);
                }
                0 => {
                    if let Some(c) = visit(m, graph, state, path) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        path.pop();
        state.insert(n.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for n in graph.keys() {
        if state.get(n).copied().unwrap_or(0) == 0 {
            if let Some(c) = visit(n, graph, &mut state, &mut Vec::new()) {
                return Some(c);
            }
        }
    }
    None
}

#[test]
fn no_crate_has_a_module_cycle() {
    for k in workspace().values() {
        let src = k.dir.join("src");
        let files = sources(k);
        // Each file's top-level module: `src/a.rs` and `src/a/…` are `a`; the crate root is
        // left out (it declares every module).
        let top = |p: &Path| -> Option<String> {
            let rel = p.strip_prefix(&src).ok()?;
            let first = rel.components().next()?.as_os_str().to_string_lossy();
            let name = first.trim_end_matches(".rs").to_string();
            (!["lib", "main"].contains(&name.as_str())).then_some(name)
        };
        let modules: BTreeSet<String> = files.iter().filter_map(|(p, _)| top(p)).collect();
        let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for (p, code) in &files {
            if let Some(m) = top(p) {
                let names = names_of_modules(code, &modules);
                graph
                    .entry(m.clone())
                    .or_default()
                    .extend(names.into_iter().filter(|n| *n != m));
            }
        }
        assert_eq!(a_cycle(&graph), None, "a module cycle in {}", k.name);
    }
}

#[test]
fn the_scan_finds_a_module_cycle() {
    let graph: BTreeMap<String, BTreeSet<String>> = [
        ("a", vec!["b"]),
        ("b", vec!["c"]),
        ("c", vec!["a"]),
        ("d", vec![]),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v.into_iter().map(String::from).collect()))
    .collect();
    assert_eq!(a_cycle(&graph).map(|c| c.len()), Some(4));
    let modules: BTreeSet<String> = ["a", "b"].into_iter().map(String::from).collect();
    let code = "use crate::a::X;\nuse crate::{b, c::Y};\nlet z = crate::zz::f();";
    assert_eq!(names_of_modules(code, &modules), modules);
}

#[test]
fn no_crate_calls_the_platforms_transcendental_functions() {
    for k in workspace().values() {
        if k.name == "dronecine-math" || k.name == "dronecine" {
            continue;
        }
        let (_, found) = dronecine_math::platform_calls_under(&k.dir.join("src"));
        assert!(
            found.is_empty(),
            "{} calls the platform's functions; call dronecine_math's instead:\n{}",
            k.name,
            found.join("\n")
        );
    }
}

/// Every code of every crate, with the namespace its crate owns.
pub(crate) fn every_code() -> Vec<(dronecine_diag::Code, &'static str)> {
    let mut codes = Vec::new();
    codes.extend(
        dronecine_grammar::PslCode::ALL
            .iter()
            .map(|c| (c.code(), "psl")),
    );
    codes.extend(
        dronecine_profile::ProfileCode::ALL
            .iter()
            .map(|c| (c.code(), "profile")),
    );
    codes.extend(
        dronecine_compiler::CompileCode::ALL
            .iter()
            .map(|c| (c.code(), "compile")),
    );
    codes.extend(
        dronecine_film::FilmCode::ALL
            .iter()
            .map(|c| (c.code(), "film")),
    );
    codes.extend(
        dronecine_natnet::rig::RigCode::ALL
            .iter()
            .map(|c| (c.code(), "rig")),
    );
    codes.extend(
        dronecine_flight::PreflightCode::ALL
            .iter()
            .map(|c| (c.code(), "preflight")),
    );
    codes
}

#[test]
fn each_crate_owns_its_codes_and_every_code_is_documented() {
    let doc = std::fs::read_to_string(crate::common::workspace().join("docs/diagnostics.md"))
        .expect("docs/diagnostics.md");
    let headings: BTreeSet<&str> = doc
        .lines()
        .filter_map(|l| l.strip_prefix("### "))
        .map(str::trim)
        .collect();
    let mut seen = BTreeSet::new();
    for (code, namespace) in every_code() {
        assert_eq!(code.namespace(), namespace, "{code}");
        assert!(seen.insert(code.as_str()), "{code} is declared twice");
        assert!(
            headings.contains(code.as_str()),
            "{code} has no `### {code}` entry in docs/diagnostics.md"
        );
    }
    let stale: Vec<&&str> = headings.iter().filter(|h| !seen.contains(**h)).collect();
    assert!(
        stale.is_empty(),
        "docs/diagnostics.md documents unknown codes {stale:?}"
    );
}

/// The repository's prose: the Markdown files and every Rust source's comments.
fn prose_files() -> Vec<PathBuf> {
    let root = crate::common::workspace();
    let out = std::process::Command::new("git")
        .args(["ls-files", "*.md", "*.rs", "*.pest", "*.toml"])
        .current_dir(root)
        .output();
    match out {
        Ok(o) if o.status.success() => String::from_utf8_lossy(&o.stdout)
            .lines()
            .map(|l| root.join(l))
            .filter(|p| p.exists())
            .collect(),
        // Not a git checkout (a source tarball): the docs at least.
        _ => ["README.md", "ARCHITECTURE.md"]
            .iter()
            .map(|f| root.join(f))
            .collect(),
    }
}

#[test]
fn the_docs_stand_alone() {
    // (This file names what it looks for.)
    let here = Path::new(file!()).file_name().expect("a file name");
    for p in prose_files()
        .into_iter()
        .filter(|p| p.file_name() != Some(here))
    {
        let text = std::fs::read_to_string(&p).unwrap_or_default();
        for outside in [
            "../shared/",
            "shared/docs",
            "psl.md",
            "camera-math.md",
            "control.md",
        ] {
            assert!(
                !text.contains(outside),
                "{} points outside the repository (`{outside}`)",
                p.display()
            );
        }
    }
}

#[test]
fn the_docs_links_lead_somewhere() {
    let root = crate::common::workspace();
    for p in prose_files()
        .into_iter()
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
    {
        let text = std::fs::read_to_string(&p).unwrap_or_default();
        for (i, _) in text.match_indices("](") {
            let target = text[i + 2..].split(')').next().unwrap_or("");
            let file = target.split('#').next().unwrap_or("");
            if file.is_empty() || file.contains("://") || file.starts_with("mailto:") {
                continue;
            }
            let resolved = p.parent().unwrap_or(root).join(file);
            assert!(
                resolved.exists(),
                "{} links to `{target}`, which does not exist",
                p.display()
            );
        }
    }
}

#[test]
fn the_front_docs_are_short() {
    let root = crate::common::workspace();
    for (file, max) in [("README.md", 10 * 1024), ("ARCHITECTURE.md", 12 * 1024)] {
        let len = std::fs::metadata(root.join(file)).map_or(0, |m| m.len());
        assert!(
            len > 0 && len <= max,
            "{file} is {len} bytes; at most {max}"
        );
    }
}
