//! Mutated versions of the scenes in `scenes/` (edited characters,
//! truncations, swapped or replaced values) never panic the loader: each
//! loads, or fails with an error naming its place.

use std::sync::OnceLock;

use proptest::prelude::*;
use proptest::sample::Index;
use render::format::SceneFile;
use render::SceneError;

use crate::support::all_scenes;

fn scenes() -> &'static [String] {
    static SCENES: OnceLock<Vec<String>> = OnceLock::new();
    SCENES.get_or_init(|| all_scenes().iter().map(|p| std::fs::read_to_string(p).unwrap()).collect())
}

/// Values likely to hit an edge: out of range, wrong type, zero, huge.
const VALUES: &[&str] = &[
    "0",
    "-1",
    "-0",
    "1e999",
    "-1e999",
    "1e-320",
    "4294967296",
    "1e308",
    "null",
    "true",
    "\"x\"",
    "\"\"",
    "[]",
    "{}",
    "[0, 0, 0]",
    "[1, 2]",
    "\"sphere\"",
    "{ \"sphere\": {} }",
    "180",
    "17",
];

/// Characters that matter to JSON, plus some that do not belong.
const CHARS: &[char] = &['{', '}', '[', ']', '"', ',', ':', '-', '.', 'e', '0', '9', ' ', 'a', '\\', 'é', '\0', '\n'];

#[derive(Clone, Debug)]
enum Edit {
    Delete(Index),
    Insert(Index, char),
    Replace(Index, char),
    Truncate(Index),
    /// Swap two tokens (runs of characters between JSON punctuation).
    Swap(Index, Index),
    /// Replace a token with one of `VALUES`.
    Value(Index, &'static str),
}

fn edit() -> impl Strategy<Value = Edit> {
    let ch = proptest::sample::select(CHARS);
    prop_oneof![
        2 => any::<Index>().prop_map(Edit::Delete),
        2 => (any::<Index>(), ch.clone()).prop_map(|(i, c)| Edit::Insert(i, c)),
        2 => (any::<Index>(), ch).prop_map(|(i, c)| Edit::Replace(i, c)),
        1 => any::<Index>().prop_map(Edit::Truncate),
        3 => (any::<Index>(), any::<Index>()).prop_map(|(i, j)| Edit::Swap(i, j)),
        4 => (any::<Index>(), proptest::sample::select(VALUES)).prop_map(|(i, v)| Edit::Value(i, v)),
    ]
}

/// Token ranges: maximal runs outside JSON punctuation and whitespace.
fn tokens(text: &[char]) -> Vec<(usize, usize)> {
    let mut v = vec![];
    let mut start = None;
    for (i, c) in text.iter().chain(std::iter::once(&' ')).enumerate() {
        let punct = "{}[],: \n\t".contains(*c);
        match (start, punct) {
            (None, false) => start = Some(i),
            (Some(s), true) => {
                v.push((s, i));
                start = None;
            }
            _ => {}
        }
    }
    v
}

fn apply(text: &mut Vec<char>, e: &Edit) {
    if text.is_empty() {
        return;
    }
    let toks = tokens(text);
    match e {
        Edit::Delete(i) => {
            text.remove(i.index(text.len()));
        }
        Edit::Insert(i, c) => text.insert(i.index(text.len() + 1), *c),
        Edit::Replace(i, c) => {
            let i = i.index(text.len());
            text[i] = *c;
        }
        Edit::Truncate(i) => text.truncate(i.index(text.len())),
        Edit::Swap(i, j) if toks.len() >= 2 => {
            let (a, b) = (toks[i.index(toks.len())], toks[j.index(toks.len())]);
            let (a, b) = if a.0 <= b.0 { (a, b) } else { (b, a) };
            if a.1 <= b.0 {
                let (ta, tb): (Vec<char>, Vec<char>) = (text[a.0..a.1].to_vec(), text[b.0..b.1].to_vec());
                text.splice(b.0..b.1, ta);
                text.splice(a.0..a.1, tb);
            }
        }
        Edit::Value(i, v) if !toks.is_empty() => {
            // Prefer values to keys (a token not followed by `:`), so that the
            // edit reaches the semantic checks rather than the syntax ones.
            let is_key = |&(_, e): &(usize, usize)| text[e..].iter().find(|c| !c.is_whitespace()) == Some(&':');
            let values: Vec<_> = toks.iter().copied().filter(|t| !is_key(t)).collect();
            let pool = if values.is_empty() { &toks } else { &values };
            let (s, e) = pool[i.index(pool.len())];
            text.splice(s..e, v.chars());
        }
        _ => {}
    }
}

proptest! {
    // Loading is cheap (no rendering of big images), so CI's case count is fine.
    #[test]
    fn mutated_scenes_load_or_name_the_place(which in any::<Index>(), edits in prop::collection::vec(edit(), 1..4)) {
        let source = &scenes()[which.index(scenes().len())];
        let mut text: Vec<char> = source.chars().collect();
        for e in &edits {
            apply(&mut text, e);
        }
        let text: String = text.into_iter().collect();
        match SceneFile::load_str(&text) {
            Ok(mut world) => {
                // A loaded world renders without panic too (tiny, few bounces: a
                // mutated max_depth could otherwise branch for ages).
                world.camera = world.camera.with_size(3, 2).unwrap();
                world.settings.max_depth = world.settings.max_depth.min(3);
                world.settings.samples = world.settings.samples.min(2);
                let (frame, _) = render::frame::render(&world, Default::default(), &|| {}).unwrap();
                prop_assert_eq!(frame.len(), 6);
            }
            Err(e) => {
                let msg = e.to_string();
                match &e {
                    SceneError::Parse { line, .. } => prop_assert!(*line >= 1 && msg.contains(", column "), "{}", msg),
                    SceneError::Semantic { place, position, .. } => {
                        prop_assert!(!place.is_empty() && msg.starts_with(place.as_str()), "{}", msg);
                        prop_assert!(position.is_some(), "no line and column: {}", msg);
                    }
                }
            }
        }
    }
}
