//! Finds where a JSON path (`blocks[1].objects[0].transform[2]`) starts in
//! the scene text, so semantic errors can give a line and column too.
//!
//! Only run on the error path; a small scanner over the (already validated)
//! text is enough, no second full parse.

enum Segment {
    Key(String),
    Index(usize),
}

/// The step into the member `name` of an object, as the paths of errors
/// write it: `.name` for a plain name (letters, digits, `_`, `-`), else
/// `["name"]` with the name as a JSON string (so `materials[".green"]`,
/// `materials["my wood"]`): a dot or bracket in a name cannot be read as
/// a step, and [`locate`] reads the path back.
pub(crate) fn key_step(name: &str) -> String {
    let plain = !name.is_empty() && name.chars().all(|c| c.is_alphanumeric() || c == '_' || c == '-');
    if plain {
        format!(".{name}")
    } else {
        // Serialising a string cannot fail.
        format!("[{}]", serde_json::to_string(name).unwrap_or_default())
    }
}

/// The steps of `path`: `name`, `.name`, `[index]` and `["name"]`.
fn segments(path: &str) -> Option<Vec<Segment>> {
    let mut out = Vec::new();
    let mut rest = path;
    loop {
        let end = rest.find(['.', '[']).unwrap_or(rest.len());
        if end > 0 {
            out.push(Segment::Key(rest[..end].to_string()));
        }
        rest = &rest[end..];
        while let Some(r) = rest.strip_prefix('[') {
            if r.starts_with('"') {
                // A JSON string: up to the first quote not escaped.
                let mut i = 1;
                while *r.as_bytes().get(i)? != b'"' {
                    i += if r.as_bytes()[i] == b'\\' { 2 } else { 1 };
                }
                out.push(Segment::Key(serde_json::from_str(r.get(..=i)?).ok()?));
                rest = r[i + 1..].strip_prefix(']')?;
            } else {
                let end = r.find(']')?;
                out.push(Segment::Index(r[..end].parse().ok()?));
                rest = &r[end + 1..];
            }
        }
        match rest.strip_prefix('.') {
            Some(r) => rest = r,
            None if rest.is_empty() => return Some(out),
            None => return None,
        }
    }
}

struct Scanner<'a> {
    b: &'a [u8],
    pos: usize,
}

impl<'a> Scanner<'a> {
    fn ws(&mut self) {
        while self.pos < self.b.len() && self.b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
    }

    fn eat(&mut self, c: u8) -> Option<()> {
        self.ws();
        (self.b.get(self.pos) == Some(&c)).then(|| self.pos += 1)
    }

    /// A key: the string's contents, escapes decoded (a name may hold any
    /// character, written as an escape or not).
    fn key(&mut self) -> Option<std::borrow::Cow<'a, str>> {
        self.ws();
        let start = self.pos;
        let raw = self.string()?;
        if raw.contains('\\') {
            let b: &'a [u8] = self.b;
            serde_json::from_slice::<String>(&b[start..self.pos]).ok().map(std::borrow::Cow::Owned)
        } else {
            Some(std::borrow::Cow::Borrowed(raw))
        }
    }

    /// A string's raw contents (escapes left as they are).
    fn string(&mut self) -> Option<&'a str> {
        self.eat(b'"')?;
        let start = self.pos;
        while *self.b.get(self.pos)? != b'"' {
            self.pos += if self.b[self.pos] == b'\\' { 2 } else { 1 };
        }
        let b: &'a [u8] = self.b;
        let s = std::str::from_utf8(&b[start..self.pos]).ok()?;
        self.pos += 1;
        Some(s)
    }

    fn skip_value(&mut self) -> Option<()> {
        self.ws();
        match *self.b.get(self.pos)? {
            b'"' => self.string().map(|_| ()),
            open @ (b'{' | b'[') => {
                let close = if open == b'{' { b'}' } else { b']' };
                self.pos += 1;
                self.ws();
                if self.b.get(self.pos) == Some(&close) {
                    self.pos += 1;
                    return Some(());
                }
                loop {
                    if open == b'{' {
                        self.string()?;
                        self.eat(b':')?;
                    }
                    self.skip_value()?;
                    self.ws();
                    match *self.b.get(self.pos)? {
                        b',' => self.pos += 1,
                        c if c == close => {
                            self.pos += 1;
                            return Some(());
                        }
                        _ => return None,
                    }
                }
            }
            _ => {
                while self.pos < self.b.len() && !b",}] \t\r\n".contains(&self.b[self.pos]) {
                    self.pos += 1;
                }
                Some(())
            }
        }
    }

    fn descend(&mut self, seg: &Segment) -> Option<()> {
        match seg {
            Segment::Key(k) => {
                self.eat(b'{')?;
                loop {
                    let key = self.key()?;
                    self.eat(b':')?;
                    if key == k.as_str() {
                        self.ws();
                        return Some(());
                    }
                    self.skip_value()?;
                    self.eat(b',')?;
                }
            }
            Segment::Index(n) => {
                self.eat(b'[')?;
                for _ in 0..*n {
                    self.skip_value()?;
                    self.eat(b',')?;
                }
                self.ws();
                Some(())
            }
        }
    }
}

/// Where a path was found: the 1-based line and column of a value, and
/// whether it is the value at the path (`exact`) or, the path leaving the
/// text, its nearest enclosing value.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Found {
    line: usize,
    column: usize,
    exact: bool,
}

/// Finds the value at `path` in `text`, or its nearest enclosing value;
/// `None` only for a path that cannot be read.
fn find(text: &str, path: &str) -> Option<Found> {
    let mut s = Scanner { b: text.as_bytes(), pos: 0 };
    let mut exact = true;
    for seg in segments(path)? {
        let start = s.pos;
        if s.descend(&seg).is_none() {
            s.pos = start;
            exact = false;
            break;
        }
    }
    s.ws();
    let before = text.get(..s.pos.min(text.len()))?;
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    Some(Found { line, column, exact })
}

/// The 1-based line and column where the value at `path` starts in `text`,
/// or, if that value is not in the text, where its nearest enclosing value
/// starts: a member left out and given its default (`camera.up`) is found
/// at its object.
pub(crate) fn locate(text: &str, path: &str) -> Option<(usize, usize)> {
    find(text, path).map(|f| (f.line, f.column))
}

#[cfg(test)]
mod tests {
    use super::{find, key_step, locate};

    const TEXT: &str = "{\n  \"a\": [1, {\"b\": \"x,]\"}, [2, 3]],\n  \"c\": {\"d\": {}, \"e\": true}\n}";

    /// The value at `path` itself (not an enclosing one) is at `want`.
    fn check(path: &str, want: Option<(usize, usize)>) {
        let exact = find(TEXT, path).filter(|f| f.exact).map(|f| (f.line, f.column));
        assert_eq!(exact, want, "{path}");
    }

    #[test]
    fn paths_resolve_to_their_value() {
        check("a", Some((2, 8)));
        check("a[0]", Some((2, 9)));
        check("a[1].b", Some((2, 18)));
        check("a[2][1]", Some((2, 30)));
        check("c", Some((3, 8)));
        check("c.e", Some((3, 23)));
        check("c.f", None);
        check("a[5]", None);
        check("c[\"e\"]", Some((3, 23)));
        check("a[1][\"b\"]", Some((2, 18)));
        check("a[1].\"b\"", None);
        check("c[\"e\"", None);
    }

    /// A path that leaves the text is located at its nearest enclosing value.
    #[test]
    fn a_missing_member_is_located_at_its_parent() {
        let at = |path: &str| locate(TEXT, path);
        for path in ["a", "a[1].b", "a[2][1]", "c.e", "c[\"e\"]"] {
            assert_eq!(find(TEXT, path).map(|f| f.exact), Some(true), "{path}");
        }
        for (path, parent) in [("c.f", "c"), ("c.d.x", "c.d"), ("a[5]", "a"), ("a[1].z", "a[1]"), ("a[0].x", "a[0]")] {
            assert_eq!(find(TEXT, path).map(|f| f.exact), Some(false), "{path}");
            assert_eq!(at(path), at(parent), "{path}");
        }
        assert_eq!(at("x.y"), Some((1, 1)));
        // A path that cannot be read is not located.
        assert_eq!(at("c[\"e\""), None);
    }

    /// A member whose name holds dots, brackets, quotes or escapes is
    /// found from the step `key_step` writes for it.
    #[test]
    fn any_name_is_found_from_its_step() {
        let names = ["green", ".green", "a.b", "x[0]", "say \"hi\"", "back\\slash", "my wood", "", "ünï", "]"];
        for name in names {
            let json = serde_json::to_string(name).expect("a string serialises");
            // As written, and with each `g` as an escape.
            for written in [json.clone(), json.replace('g', "\\u0067")] {
                let text = format!("{{\"m\": {{\"other\": 1, {written}: {{\"ambient\": 7}}}}}}");
                let path = format!("m{}.ambient", key_step(name));
                let found = find(&text, &path).filter(|f| f.exact);
                let (line, column) =
                    found.map(|f| (f.line, f.column)).unwrap_or_else(|| panic!("{path} not found in {text}"));
                assert_eq!(line, 1);
                // Columns count characters.
                assert_eq!(text.chars().nth(column - 1), Some('7'), "{path} in {text}");
            }
        }
        assert_eq!(key_step("green"), ".green");
        assert_eq!(key_step(".green"), "[\".green\"]");
    }
}
