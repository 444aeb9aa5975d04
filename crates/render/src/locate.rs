//! Finds where a JSON path (`blocks[1].objects[0].transform[2]`) starts in
//! the scene text, so semantic errors can give a line and column too.
//!
//! Only run on the error path; a small scanner over the (already validated)
//! text is enough, no second full parse.

enum Segment<'a> {
    Key(&'a str),
    Index(usize),
}

fn segments(path: &str) -> Option<Vec<Segment<'_>>> {
    let mut out = Vec::new();
    for part in path.split('.') {
        let (name, mut rest) = match part.find('[') {
            Some(i) => (&part[..i], &part[i..]),
            None => (part, ""),
        };
        if !name.is_empty() {
            out.push(Segment::Key(name));
        }
        while let Some(r) = rest.strip_prefix('[') {
            let end = r.find(']')?;
            out.push(Segment::Index(r[..end].parse().ok()?));
            rest = &r[end + 1..];
        }
    }
    Some(out)
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

    /// A string's raw contents (escapes are left as they are: keys in scene
    /// files are plain names).
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
                    let key = self.string()?;
                    self.eat(b':')?;
                    if key == *k {
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

/// The 1-based line and column where the value at `path` starts in `text`.
pub(crate) fn locate(text: &str, path: &str) -> Option<(usize, usize)> {
    let mut s = Scanner { b: text.as_bytes(), pos: 0 };
    for seg in segments(path)? {
        s.descend(&seg)?;
    }
    s.ws();
    let before = text.get(..s.pos.min(text.len()))?;
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    Some((line, column))
}

#[cfg(test)]
mod tests {
    use super::locate;

    fn check(path: &str, want: Option<(usize, usize)>) {
        let text = "{\n  \"a\": [1, {\"b\": \"x,]\"}, [2, 3]],\n  \"c\": {\"d\": {}, \"e\": true}\n}";
        assert_eq!(locate(text, path), want, "{path}");
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
    }
}
