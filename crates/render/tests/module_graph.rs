//! The modules of `render` form a DAG: no module reaches itself through
//! the modules it uses. A reader can then take the crate a layer at a time,
//! from `limits` and `locate` up to `bench`, and a change to a module can
//! only affect the layers above it.
//!
//! The test reads `src/*.rs` (and each `src/<module>/*.rs` as one module) as text: a module uses another where it names
//! `crate::<module>` outside its tests (`#[cfg(test)]` items) and outside
//! comments and literals. It also refuses `crate::<item>` of an item the
//! root re-exports (`crate::Error`): such a use hides the module it comes
//! from, and with it an edge of the graph.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Each module's source (`lib.rs` and test-only modules left out).
type Sources = BTreeMap<String, String>;

/// The modules `render` is made of, read from `src/`.
fn sources() -> Sources {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let lib = std::fs::read_to_string(src.join("lib.rs")).expect("lib.rs is readable");
    let test_only = test_only_modules(&lib);
    let mut modules = Sources::new();
    for entry in std::fs::read_dir(&src).expect("src/ is readable") {
        let path = entry.expect("src/ lists").path();
        let Some(name) = path.file_stem().and_then(|s| s.to_str()) else { continue };
        if path.extension().is_some_and(|e| e == "rs") && name != "lib" && !test_only.contains(name) {
            modules.insert(name.to_string(), std::fs::read_to_string(&path).expect("a module is readable"));
        } else if path.join("mod.rs").is_file() {
            // A module of several files (`openmc/`) is one node: its files'
            // text together (their `super::` uses stay inside it).
            let mut files: Vec<_> =
                std::fs::read_dir(&path).expect("a module directory lists").flatten().map(|e| e.path()).collect();
            files.sort();
            let text: String = files
                .iter()
                .filter(|f| f.extension().is_some_and(|e| e == "rs"))
                .map(|f| std::fs::read_to_string(f).expect("a module is readable"))
                .collect::<Vec<_>>()
                .join("\n");
            modules.insert(name.to_string(), text.replace("super::", "self::"));
        }
    }
    modules
}

/// The modules `lib.rs` declares only for tests (`#[cfg(test)] mod x;`).
fn test_only_modules(lib: &str) -> BTreeSet<String> {
    let code = strip(lib);
    let mut out = BTreeSet::new();
    let mut rest = code.as_str();
    while let Some(i) = rest.find("#[cfg(test)]") {
        rest = rest[i + "#[cfg(test)]".len()..].trim_start();
        if let Some(decl) = rest.strip_prefix("mod ") {
            let name: String = decl.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
            out.insert(name);
        }
    }
    out
}

/// `text` with comments removed and the contents of string and character
/// literals blanked (their delimiters kept), so that neither a `crate::`
/// in a comment or string nor a brace in a literal is read as code.
fn strip(text: &str) -> String {
    let b: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        let next = b.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < b.len() && b[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            // Block comments nest in Rust.
            let mut depth = 0;
            while i < b.len() {
                if b[i] == '/' && b.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if b[i] == '*' && b.get(i + 1) == Some(&'/') {
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
        } else if c == 'r' && matches!(next, Some('"' | '#')) && !ident_before(&b, i) && raw_string_at(&b, i).is_some()
        {
            // r"…" or r#"…"#: up to the quote followed by as many hashes.
            let hashes = raw_string_at(&b, i).unwrap_or(0);
            i += 2 + hashes;
            let close: String = std::iter::once('"').chain(std::iter::repeat_n('#', hashes)).collect();
            let close: Vec<char> = close.chars().collect();
            while i < b.len() && b[i..].iter().take(close.len()).ne(close.iter()) {
                i += 1;
            }
            i += close.len();
            out.push_str("\"\"");
        } else if c == '"' {
            i += 1;
            while i < b.len() && b[i] != '"' {
                i += if b[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("\"\"");
        } else if c == '\'' && char_literal_len(&b, i).is_some() {
            i += char_literal_len(&b, i).unwrap_or(1);
            out.push_str("' '");
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

fn ident_before(b: &[char], i: usize) -> bool {
    i > 0 && (b[i - 1].is_alphanumeric() || b[i - 1] == '_')
}

/// The number of `#` of a raw string starting at `b[i] == 'r'`, if one does.
fn raw_string_at(b: &[char], i: usize) -> Option<usize> {
    let hashes = b[i + 1..].iter().take_while(|c| **c == '#').count();
    (b.get(i + 1 + hashes) == Some(&'"')).then_some(hashes)
}

/// The length of a character literal starting at `b[i] == '\''`, if one
/// does (else it is a lifetime).
fn char_literal_len(b: &[char], i: usize) -> Option<usize> {
    if b.get(i + 1) == Some(&'\\') {
        let end = b[i + 2..].iter().position(|c| *c == '\'')?;
        return Some(end + 3);
    }
    (b.get(i + 2) == Some(&'\'')).then_some(3)
}

/// `code` (already [`strip`]ped) without its `#[cfg(test)]` items: the
/// attribute, any attributes after it, and the item up to its `;` or the
/// end of its `{ … }` block.
fn without_tests(code: &str) -> String {
    const ATTR: &str = "#[cfg(test)]";
    let b: Vec<char> = code.chars().collect();
    let mut out = String::new();
    let mut rest = code;
    while let Some(at) = rest.find(ATTR) {
        out.push_str(&rest[..at]);
        let start = code.len() - rest.len() + at + ATTR.len();
        let start = code[..start].chars().count();
        let mut i = start;
        let (mut depth, mut braces) = (0i32, false);
        while i < b.len() {
            match b[i] {
                '(' | '[' => depth += 1,
                ')' | ']' => depth -= 1,
                '{' => {
                    depth += 1;
                    braces = true;
                }
                '}' => {
                    depth -= 1;
                    if depth == 0 && braces {
                        i += 1;
                        break;
                    }
                }
                ';' if depth == 0 => {
                    i += 1;
                    break;
                }
                _ => {}
            }
            i += 1;
        }
        let skipped: usize = b[..i].iter().map(|c| c.len_utf8()).sum();
        rest = &code[skipped..];
    }
    out.push_str(rest);
    out
}

/// The first path segment of every `crate::…` (and `super::…`, the root
/// for a top-level module) in `code`; `crate::{a::x, b}` names `a` and `b`.
fn crate_paths(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    for prefix in ["crate::", "super::"] {
        let mut from = 0;
        while let Some(at) = code[from..].find(prefix) {
            let start = from + at;
            from = start + prefix.len();
            let before = code[..start].chars().next_back();
            if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '$' || c == ':') {
                continue;
            }
            let rest = &code[from..];
            if let Some(group) = rest.strip_prefix('{') {
                // Top-level entries of the group, up to its closing brace.
                let (mut depth, mut entry_start, mut entries) = (0, 0, Vec::new());
                for (k, c) in group.char_indices() {
                    match c {
                        '{' => depth += 1,
                        '}' if depth == 0 => {
                            entries.push(&group[entry_start..k]);
                            break;
                        }
                        '}' => depth -= 1,
                        ',' if depth == 0 => {
                            entries.push(&group[entry_start..k]);
                            entry_start = k + 1;
                        }
                        _ => {}
                    }
                }
                out.extend(entries.into_iter().map(first_ident).filter(|s| !s.is_empty()));
            } else {
                out.push(first_ident(rest));
            }
        }
    }
    out
}

fn first_ident(s: &str) -> String {
    s.trim_start().chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect()
}

/// Module → the modules it uses; or the uses of root items, which hide a
/// module.
fn graph(sources: &Sources) -> Result<BTreeMap<String, BTreeSet<String>>, Vec<String>> {
    let mut edges = BTreeMap::new();
    let mut hidden = Vec::new();
    for (module, text) in sources {
        let mut uses = BTreeSet::new();
        for name in crate_paths(&without_tests(&strip(text))) {
            if sources.contains_key(&name) {
                if &name != module {
                    uses.insert(name);
                }
            } else {
                hidden.push(format!("{module}.rs names crate::{name}, not a module: name the module it comes from"));
            }
        }
        edges.insert(module.clone(), uses);
    }
    if hidden.is_empty() {
        Ok(edges)
    } else {
        Err(hidden)
    }
}

/// A cycle of `edges`, as the modules along it (the first repeated at the
/// end), if there is one.
fn cycle(edges: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    #[derive(Clone, Copy, PartialEq)]
    enum State {
        New,
        OnPath,
        Done,
    }
    fn visit<'a>(
        m: &'a str,
        edges: &'a BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<&'a str, State>,
        path: &mut Vec<&'a str>,
    ) -> Option<Vec<String>> {
        state.insert(m, State::OnPath);
        path.push(m);
        for next in edges.get(m).into_iter().flatten() {
            match state.get(next.as_str()).copied().unwrap_or(State::New) {
                State::OnPath => {
                    let from = path.iter().position(|p| p == next).unwrap_or(0);
                    let mut c: Vec<String> = path[from..].iter().map(|s| s.to_string()).collect();
                    c.push(next.clone());
                    return Some(c);
                }
                State::New => {
                    if let Some(c) = visit(next, edges, state, path) {
                        return Some(c);
                    }
                }
                State::Done => {}
            }
        }
        path.pop();
        state.insert(m, State::Done);
        None
    }
    let mut state = BTreeMap::new();
    for m in edges.keys() {
        if state.get(m.as_str()).copied().unwrap_or(State::New) == State::New {
            if let Some(c) = visit(m, edges, &mut state, &mut Vec::new()) {
                return Some(c);
            }
        }
    }
    None
}

/// The layers of an acyclic graph: layer 0 uses no module, layer n uses
/// some module of layer n − 1 and none above.
fn layers(edges: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    let mut level: BTreeMap<&str, usize> = BTreeMap::new();
    while level.len() < edges.len() {
        for (m, uses) in edges {
            if !level.contains_key(m.as_str()) && uses.iter().all(|u| level.contains_key(u.as_str())) {
                let l = uses.iter().map(|u| level[u.as_str()] + 1).max().unwrap_or(0);
                level.insert(m, l);
            }
        }
    }
    let mut out = vec![Vec::new(); level.values().max().map_or(0, |l| l + 1)];
    for (m, l) in level {
        out[l].push(m.to_string());
    }
    out
}

#[test]
fn the_modules_of_render_form_a_dag() {
    let sources = sources();
    let edges = graph(&sources).unwrap_or_else(|hidden| panic!("{}", hidden.join("\n")));
    if let Some(c) = cycle(&edges) {
        panic!("the modules of render use each other in a circle: {}", c.join(" -> "));
    }
    // The graph is read, not vacuous: a few edges every version has.
    for (from, to) in [("frame", "shade"), ("shade", "world"), ("convert", "flatten"), ("exr", "output")] {
        assert!(edges[from].contains(to), "{from} -> {to} not found: {edges:?}");
    }
    for (l, modules) in layers(&edges).iter().enumerate() {
        println!("layer {l}: {}", modules.join(", "));
    }
}

/// Builds [`Sources`] from `(module, text)` pairs.
fn modules(pairs: &[(&str, &str)]) -> Sources {
    pairs.iter().map(|(m, t)| (m.to_string(), t.to_string())).collect()
}

#[test]
fn a_cycle_is_found_and_named() {
    let sources = modules(&[
        ("a", "use crate::b::X;"),
        ("b", "fn f() { crate::c::g() }"),
        ("c", "use crate::{a::Y, d};"),
        ("d", ""),
    ]);
    let edges = graph(&sources).unwrap_or_else(|e| panic!("{e:?}"));
    assert_eq!(cycle(&edges), Some(vec!["a".into(), "b".into(), "c".into(), "a".into()]));
}

#[test]
fn tests_comments_and_literals_are_not_uses() {
    let text = r##"
        use crate::b::X; // crate::c in a comment
        /* crate::c /* nested */ crate::c */
        /// [`crate::c::Doc`]
        const S: &str = "crate::c::{";
        const R: &str = r#"crate::c "quoted" }"#;
        const C: char = '{';
        fn f<'a>(x: &'a str) -> &'a str { x }
        macro_rules! m { () => { $crate::c::X }; }
        #[cfg(test)]
        use crate::c::Y;
        #[cfg(test)]
        #[allow(clippy::unwrap_used)]
        mod tests {
            use crate::c::Z;
            const T: &str = "}";
        }
        fn g() -> crate::d::Y { todo!() }
    "##;
    let sources = modules(&[("a", text), ("b", ""), ("c", "use crate::a::A;"), ("d", "")]);
    let edges = graph(&sources).unwrap_or_else(|e| panic!("{e:?}"));
    assert_eq!(edges["a"], BTreeSet::from(["b".to_string(), "d".to_string()]));
    assert_eq!(cycle(&edges), None);
}

#[test]
fn a_root_item_is_refused_for_hiding_its_module() {
    let sources = modules(&[("a", "use crate::Error;\nfn f() { super::load() }"), ("error", "")]);
    let hidden = graph(&sources).err().unwrap_or_default();
    assert_eq!(hidden.len(), 2, "{hidden:?}");
    assert!(hidden[0].contains("crate::Error") && hidden[1].contains("crate::load"), "{hidden:?}");
}

#[test]
fn layers_put_each_module_one_above_its_highest_use() {
    let sources = modules(&[("a", "use crate::b::X; use crate::c::Y;"), ("b", "use crate::c::Z;"), ("c", "")]);
    let edges = graph(&sources).unwrap_or_else(|e| panic!("{e:?}"));
    assert_eq!(layers(&edges), vec![vec!["c".to_string()], vec!["b".to_string()], vec!["a".to_string()]]);
}

#[test]
fn lib_rs_test_modules_are_left_out() {
    let lib = "pub mod a;\n#[cfg(test)]\nmod graph_tests;\n// #[cfg(test)] mod commented;\nmod b;";
    assert_eq!(test_only_modules(lib), BTreeSet::from(["graph_tests".to_string()]));
}
