//! The core's modules form layers: no module file reaches itself through the imports of others.
//!
//! The checker reads the source, not the compiler's output, so it runs on any folder of module files (the
//! fixtures under `tests/fixtures/layers` prove it finds a circle and accepts a tree). One node per module file
//! (`lib.rs`, `foo.rs`, `foo/mod.rs`, `foo/bar.rs`); an edge from a file to every module file whose items it
//! names: in `use` trees (`crate::`, `super::`, `self::` and child-module paths, grouped, renamed or globbed)
//! and in code (`crate::a::f()`, `super::super::g`). A path is followed to the module file that defines its
//! item: through the modules it names and through the `use` items (re-exports included) of the module it
//! ends in, so `crate::VoxelModel` is an edge to `model.rs`, not to `lib.rs`. Declaring a child (`mod child;`)
//! is no edge; a child naming its parent's items (`super::X`) is, so a parent that imports from a child the
//! child imports from is a circle. Comments, string and char literals and `#[cfg(test)]` items are skipped:
//! a module's tests may drive the pipeline above it. Limits (none used in the core): `super::` inside an
//! inline module means the file's module, `#[path]` modules are not followed, and paths written with spaces
//! around `::` are not read.

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::path::{Path, PathBuf};

/// A module's path from the crate root: `[]` for `lib.rs`, `["cli", "report"]` for `cli/report.rs`.
type ModulePath = Vec<String>;

/// One `use` leaf: the path it names (as written) and the name it brings into scope (`None` for a glob).
#[derive(Debug)]
struct UseLeaf {
    path: Vec<String>,
    name: Option<String>,
}

/// A module file, read.
struct ModuleFile {
    /// The file, relative to the source folder (`cli/mod.rs`).
    file: String,
    /// Its `use` leaves, from every `use` declaration outside `#[cfg(test)]` items.
    uses: Vec<UseLeaf>,
    /// The paths its code names (outside `use` declarations), each at least two segments long.
    code_paths: Vec<Vec<String>>,
    /// The names of the items it defines (`fn`, `struct`, `enum`, `const`, …).
    items: BTreeSet<String>,
}

/// The module files of a crate's source folder, by module path.
struct Crate {
    modules: BTreeMap<ModulePath, ModuleFile>,
}

/// The edges between module files, by file name (relative to the source folder).
type Graph = BTreeMap<String, BTreeSet<String>>;

impl Crate {
    /// Reads every `.rs` file under `src` (the folder of `lib.rs`).
    fn read(src: &Path) -> Self {
        let mut files = Vec::new();
        collect_rs_files(src, &mut files);
        let modules = files
            .into_iter()
            .map(|path| {
                let relative = path.strip_prefix(src).expect("under src");
                let file = relative.components().map(|c| c.as_os_str().to_string_lossy()).collect::<Vec<_>>().join("/");
                let source = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                (module_path(relative), parse_module(file, &source))
            })
            .collect();
        Self { modules }
    }

    /// The import graph: every module file with the module files it names.
    fn graph(&self) -> Graph {
        let mut graph = Graph::new();
        for (here, module) in &self.modules {
            let targets = graph.entry(module.file.clone()).or_default();
            let named = module.uses.iter().map(|leaf| &leaf.path).chain(&module.code_paths);
            for path in named {
                let Some(target) = self.absolute(here, path).and_then(|path| self.defining_module(&path, 0)) else {
                    continue;
                };
                if &target != here {
                    targets.insert(self.modules[&target].file.clone());
                }
            }
        }
        graph
    }

    /// `path` as written in module `here`, from the crate root; `None` when it starts outside the crate (another
    /// crate, or a name in scope that is not a child module).
    fn absolute(&self, here: &ModulePath, path: &[String]) -> Option<Vec<String>> {
        let (first, rest) = path.split_first()?;
        let mut base = here.clone();
        let mut rest = rest;
        match first.as_str() {
            "crate" => base.clear(),
            "self" => {}
            "super" => {
                base.pop()?;
                while let Some(("super", after)) = rest.split_first().map(|(s, r)| (s.as_str(), r)) {
                    base.pop()?;
                    rest = after;
                }
            }
            child => {
                base.push(child.to_owned());
                if !self.modules.contains_key(&base) {
                    return None;
                }
            }
        }
        base.extend(rest.iter().cloned());
        Some(base)
    }

    /// The module file that defines what the absolute `path` names: the deepest module file on it, or, when the
    /// path goes on to an item that module imports, wherever that import leads.
    fn defining_module(&self, path: &[String], depth: usize) -> Option<ModulePath> {
        assert!(depth < 32, "re-exports in a loop at {path:?}");
        let mut module = ModulePath::new();
        let mut at = 0;
        while at < path.len() && self.modules.contains_key(&[module.as_slice(), &path[at..=at]].concat()) {
            module.push(path[at].clone());
            at += 1;
        }
        let Some(name) = path.get(at) else { return Some(module) };
        let uses = &self.modules.get(&module)?.uses;
        if let Some(leaf) = uses.iter().find(|leaf| leaf.name.as_ref() == Some(name)) {
            let source = self.absolute(&module, &leaf.path)?;
            return self.defining_module(&[source.as_slice(), &path[at + 1..]].concat(), depth + 1);
        }
        // Through a glob import, when the globbed module has the name itself (a child module or an import).
        for glob in uses.iter().filter(|leaf| leaf.name.is_none()) {
            if let Some(source) = self.absolute(&module, &glob.path).filter(|s| self.has_name(s, name)) {
                return self.defining_module(&[source.as_slice(), &path[at..]].concat(), depth + 1);
            }
        }
        Some(module)
    }

    /// Whether module `module` has a child module, an import or an item called `name`.
    fn has_name(&self, module: &[String], name: &str) -> bool {
        self.modules.contains_key(&[module, &[name.to_owned()]].concat())
            || self
                .modules
                .get(module)
                .is_some_and(|m| m.items.contains(name) || m.uses.iter().any(|leaf| leaf.name.as_deref() == Some(name)))
    }
}

/// Every `.rs` file under `dir`, sorted.
fn collect_rs_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|entry| entry.expect("a folder entry").path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            collect_rs_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The module path of a file relative to the source folder.
fn module_path(relative: &Path) -> ModulePath {
    let mut path: ModulePath = relative.components().map(|c| c.as_os_str().to_string_lossy().into_owned()).collect();
    let file = path.pop().expect("a file name");
    match file.as_str() {
        "lib.rs" | "main.rs" if path.is_empty() => {}
        "mod.rs" => {}
        _ => path.push(file.trim_end_matches(".rs").to_owned()),
    }
    path
}

/// Reads a module file's `use` leaves and code paths.
fn parse_module(file: String, source: &str) -> ModuleFile {
    let code = without_test_items(&without_comments_and_literals(source));
    let tokens = tokenize(&code);
    let mut uses = Vec::new();
    let mut code_paths = Vec::new();
    let items = tokens
        .windows(2)
        .filter(|pair| ITEM_KEYWORDS.contains(&pair[0].as_str()) && is_ident(&pair[1]))
        .map(|pair| pair[1].clone())
        .collect();
    let mut i = 0;
    while i < tokens.len() {
        if tokens[i] == "use" {
            let end = tokens[i..].iter().position(|t| t == ";").map_or(tokens.len(), |k| i + k);
            let mut at = i + 1;
            parse_use_tree(&tokens[..end], &mut at, Vec::new(), &mut uses);
            i = end + 1;
            continue;
        }
        let starts_path = is_ident(&tokens[i]) && (i == 0 || tokens[i - 1] != "::");
        if starts_path {
            let mut path = vec![tokens[i].clone()];
            let mut at = i + 1;
            while at + 1 < tokens.len() && tokens[at] == "::" && is_ident(&tokens[at + 1]) {
                path.push(tokens[at + 1].clone());
                at += 2;
            }
            if path.len() >= 2 {
                code_paths.push(path);
            }
            i = at;
            continue;
        }
        i += 1;
    }
    ModuleFile { file, uses, code_paths, items }
}

/// The keywords that introduce a named item.
const ITEM_KEYWORDS: [&str; 8] = ["fn", "struct", "enum", "const", "static", "type", "trait", "union"];

/// Parses one use tree from `tokens[*at..]` under `prefix`, adding its leaves to `out`.
fn parse_use_tree(tokens: &[String], at: &mut usize, mut prefix: Vec<String>, out: &mut Vec<UseLeaf>) {
    while let Some(token) = tokens.get(*at) {
        *at += 1;
        match token.as_str() {
            "::" => {}
            "*" => return out.push(UseLeaf { path: prefix, name: None }),
            "{" => {
                while tokens.get(*at).is_some_and(|t| t != "}") {
                    parse_use_tree(tokens, at, prefix.clone(), out);
                    if tokens.get(*at).is_some_and(|t| t == ",") {
                        *at += 1;
                    }
                }
                *at += 1;
                return;
            }
            ident if tokens.get(*at).is_some_and(|t| t == "::") => prefix.push(ident.to_owned()),
            ident => {
                let alias = (tokens.get(*at).is_some_and(|t| t == "as")).then(|| {
                    *at += 2;
                    tokens[*at - 1].clone()
                });
                if ident != "self" {
                    prefix.push(ident.to_owned());
                }
                let name = alias.or_else(|| prefix.last().cloned());
                return out.push(UseLeaf { path: prefix, name });
            }
        }
    }
}

/// Whether `token` is an identifier (or a keyword).
fn is_ident(token: &str) -> bool {
    token.chars().next().is_some_and(|c| c.is_alphabetic() || c == '_')
}

/// The tokens of `code` that matter for paths: identifiers, `::`, and single punctuation characters.
fn tokenize(code: &str) -> Vec<String> {
    let chars: Vec<char> = code.chars().collect();
    let mut tokens = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_alphanumeric() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            tokens.push(chars[start..i].iter().collect());
        } else if c == ':' && chars.get(i + 1) == Some(&':') {
            tokens.push("::".to_owned());
            i += 2;
        } else {
            if !c.is_whitespace() {
                tokens.push(c.to_string());
            }
            i += 1;
        }
    }
    tokens
}

/// `source` with comments removed and string and char literals emptied (`""`, `' '`); lines are kept.
fn without_comments_and_literals(source: &str) -> String {
    let chars: Vec<char> = source.chars().collect();
    let ident_before = |i: usize| i > 0 && (chars[i - 1].is_alphanumeric() || chars[i - 1] == '_');
    let mut out = String::with_capacity(source.len());
    let mut i = 0;
    while i < chars.len() {
        let (c, next) = (chars[i], chars.get(i + 1).copied());
        if c == '/' && next == Some('/') {
            while i < chars.len() && chars[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < chars.len() {
                if chars[i] == '/' && chars.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if chars[i] == '*' && chars.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
            out.push(' ');
        } else if c == 'r' && matches!(next, Some('"' | '#')) && (!ident_before(i) || is_byte_prefix(&chars, i)) {
            // A raw string r"…", r#"…"# (or br"…"), else a raw identifier r#name.
            let mut j = i + 1;
            while chars.get(j) == Some(&'#') {
                j += 1;
            }
            if chars.get(j) != Some(&'"') {
                out.push(c);
                i += 1;
                continue;
            }
            let closing: String = std::iter::once('"').chain(std::iter::repeat_n('#', j - i - 1)).collect();
            let rest: String = chars[j + 1..].iter().collect();
            let end = rest.find(&closing).map_or(chars.len(), |k| j + 1 + rest[..k].chars().count() + closing.len());
            out.push_str("\"\"");
            i = end;
        } else if c == '"' {
            i += 1;
            while i < chars.len() && chars[i] != '"' {
                i += if chars[i] == '\\' { 2 } else { 1 };
            }
            out.push_str("\"\"");
            i += 1;
        } else if c == '\'' && next == Some('\\') {
            // An escaped char literal: '\n', '\'', '\u{…}'.
            i += 2;
            while i < chars.len() && chars[i] != '\'' {
                i += 1;
            }
            out.push_str("' '");
            i += 1;
        } else if c == '\'' && chars.get(i + 2) == Some(&'\'') {
            out.push_str("' '");
            i += 3;
        } else {
            out.push(c); // a lifetime's quote, or any other character
            i += 1;
        }
    }
    out
}

/// Whether the `r` at `i` follows a lone `b` (a raw byte string `br"…"`).
fn is_byte_prefix(chars: &[char], i: usize) -> bool {
    i >= 1 && chars[i - 1] == 'b' && (i < 2 || !(chars[i - 2].is_alphanumeric() || chars[i - 2] == '_'))
}

/// `code` (without comments and literals) with every item marked `#[cfg(test)]` removed, its other
/// attributes included: up to its `;`, or to the brace that closes its body.
fn without_test_items(code: &str) -> String {
    const MARK: &str = "#[cfg(test)]";
    let mut out = String::with_capacity(code.len());
    let mut rest = code;
    while let Some(start) = rest.find(MARK) {
        out.push_str(&rest[..start]);
        let item = &rest[start + MARK.len()..];
        let mut depth = 0usize;
        let mut end = item.len();
        for (k, c) in item.char_indices() {
            match c {
                '{' | '[' | '(' => depth += 1,
                '}' | ']' | ')' => {
                    depth = depth.saturating_sub(1);
                    if depth == 0 && c == '}' {
                        end = k + 1;
                        break;
                    }
                }
                ';' if depth == 0 => {
                    end = k + 1;
                    break;
                }
                _ => {}
            }
        }
        rest = &item[end..];
    }
    out.push_str(rest);
    out
}

/// The circles of `graph`: one shortest circle (`a.rs → b.rs → a.rs`) per set of files that reach each other,
/// followed by the set when the circle does not pass through all of it.
fn circles(graph: &Graph) -> Vec<String> {
    let reach = |from: &str| -> BTreeSet<String> {
        let mut seen = BTreeSet::new();
        let mut queue: VecDeque<&str> = VecDeque::from([from]);
        while let Some(node) = queue.pop_front() {
            for next in graph.get(node).into_iter().flatten() {
                if seen.insert(next.clone()) {
                    queue.push_back(next);
                }
            }
        }
        seen
    };
    let reachable: BTreeMap<&str, BTreeSet<String>> = graph.keys().map(|n| (n.as_str(), reach(n))).collect();
    let mut reported = BTreeSet::new();
    let mut out = Vec::new();
    for (node, reached) in &reachable {
        if !reached.contains(*node) || reported.contains(*node) {
            continue;
        }
        // The files that reach `node` and that it reaches: its circle's members.
        let members: BTreeSet<&str> =
            reached.iter().map(String::as_str).filter(|m| reachable[m].contains(*node)).collect();
        reported.extend(members.iter().map(|m| m.to_string()));
        let circle = shortest_circle(graph, node, &members);
        let all: Vec<&str> = members.iter().copied().collect();
        if circle.matches(" → ").count() < all.len() {
            out.push(format!("{circle} (in a knot of {}: {})", all.len(), all.join(", ")));
        } else {
            out.push(circle);
        }
    }
    out
}

/// The shortest way from `node` back to itself through `members`, written `a.rs → b.rs → a.rs`.
fn shortest_circle(graph: &Graph, node: &str, members: &BTreeSet<&str>) -> String {
    let mut came_from: BTreeMap<&str, &str> = BTreeMap::new();
    let mut queue: VecDeque<&str> = VecDeque::from([node]);
    'search: while let Some(at) = queue.pop_front() {
        for next in graph[at].iter().map(String::as_str).filter(|n| members.contains(n)) {
            if next == node {
                came_from.insert(node, at);
                break 'search;
            }
            if !came_from.contains_key(next) {
                came_from.insert(next, at);
                queue.push_back(next);
            }
        }
    }
    let mut way = vec![node];
    let mut at = came_from[node];
    while at != node {
        way.push(at);
        at = came_from[at];
    }
    way.push(node);
    way.reverse();
    way.join(" → ")
}

/// The folder of voxel-core's Cargo.toml.
fn manifest_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The fixture crate `tests/fixtures/layers/<name>`, read.
fn fixture(name: &str) -> Crate {
    Crate::read(&manifest_dir().join("tests/fixtures/layers").join(name))
}

/// The graph's edges as `from → to` lines.
fn edges(graph: &Graph) -> Vec<String> {
    graph.iter().flat_map(|(from, tos)| tos.iter().map(move |to| format!("{from} → {to}"))).collect()
}

#[test]
fn the_core_has_no_import_circle() {
    let graph = Crate::read(&manifest_dir().join("src")).graph();
    let circles = circles(&graph);
    assert!(circles.is_empty(), "import circles in voxel-core:\n{}", circles.join("\n"));
    // The walk read the real imports: a few edges every layering has.
    let edges = edges(&graph);
    for edge in ["voxelize.rs → fill.rs", "fill.rs → columns.rs", "orient.rs → columns.rs", "cli/mod.rs → voxelize.rs"]
    {
        assert!(edges.iter().any(|e| e == edge), "no edge {edge} in {edges:#?}");
    }
    assert!(graph.len() >= 40 && edges.len() >= 100, "{} files, {} edges", graph.len(), edges.len());
}

#[test]
fn a_circle_through_re_exports_and_code_paths_is_found_and_named() {
    let circles = circles(&fixture("circle").graph());
    assert_eq!(
        circles,
        [
            // a.rs names crate::Thing (lib.rs re-exports b's), b.rs calls super::c::helper, c.rs imports a's Leaf.
            "a.rs → b.rs → c.rs → a.rs",
            // A parent importing from its child, which imports from its parent.
            "parent/child.rs → parent/mod.rs → parent/child.rs",
        ]
    );
}

#[test]
fn a_layered_crate_passes_with_exactly_its_edges() {
    let graph = fixture("layered").graph();
    assert!(circles(&graph).is_empty(), "{:?}", circles(&graph));
    // Comments, strings, chars, `#[cfg(test)]` items and `mod` declarations give no edge; grouped, renamed,
    // `self`, glob and nested `super` paths and re-exports through two modules resolve to where items live.
    assert_eq!(
        edges(&graph),
        [
            "high.rs → leaf.rs",
            "high.rs → mid/inner.rs",
            "high.rs → mid/mod.rs",
            "lib.rs → high.rs",
            "lib.rs → mid/inner.rs",
            "mid/inner.rs → leaf.rs",
            "mid/mod.rs → leaf.rs",
            "mid/mod.rs → mid/inner.rs",
            "mid/sibling.rs → leaf.rs",
            "mid/sibling.rs → mid/inner.rs",
        ]
    );
}
