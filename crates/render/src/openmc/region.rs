//! OpenMC region expressions: parsing (`[+|-]id`, whitespace for
//! intersection, `|`, `~`, parentheses; precedence parentheses > `~` >
//! intersection > union) and the union of intersections a cell becomes
//! (complements pushed down to the half-spaces by De Morgan's laws).

/// A region expression.
#[derive(Clone, Debug, PartialEq)]
pub enum Expr {
    /// A half-space: the surface id and whether it is the `+` side.
    Half(u64, bool),
    /// `~e`.
    Not(Box<Expr>),
    /// The intersection of all.
    And(Vec<Expr>),
    /// The union of all.
    Or(Vec<Expr>),
}

/// A half-space of a term: surface id and side (`true` = `+`).
pub type Half = (u64, bool);

/// Most terms a cell's region may expand to.
pub const MAX_TERMS: usize = 4096;

impl Expr {
    /// Every surface id the expression names.
    pub fn surfaces(&self) -> Vec<u64> {
        let mut out = Vec::new();
        self.visit(&mut |s| out.push(s));
        out
    }

    fn visit(&self, f: &mut impl FnMut(u64)) {
        match self {
            Expr::Half(s, _) => f(*s),
            Expr::Not(e) => e.visit(f),
            Expr::And(v) | Expr::Or(v) => v.iter().for_each(|e| e.visit(f)),
        }
    }

    /// The region as a union of intersections of half-spaces, each term
    /// without repeats and without a surface on both sides (such a term is
    /// empty and dropped); an error past [`MAX_TERMS`] terms.
    pub fn terms(&self) -> Result<Vec<Vec<Half>>, String> {
        let mut terms = self.dnf(false)?;
        for t in &mut terms {
            t.sort_unstable();
            t.dedup();
        }
        terms.retain(|t| !t.windows(2).any(|w| w[0].0 == w[1].0));
        terms.sort();
        terms.dedup();
        Ok(terms)
    }

    fn dnf(&self, negated: bool) -> Result<Vec<Vec<Half>>, String> {
        match (self, negated) {
            (Expr::Half(s, plus), _) => Ok(vec![vec![(*s, *plus != negated)]]),
            (Expr::Not(e), _) => e.dnf(!negated),
            (Expr::Or(v), false) | (Expr::And(v), true) => {
                let mut out = Vec::new();
                for e in v {
                    out.extend(e.dnf(negated)?);
                    if out.len() > MAX_TERMS {
                        return Err(too_many());
                    }
                }
                Ok(out)
            }
            (Expr::And(v), false) | (Expr::Or(v), true) => {
                let mut out: Vec<Vec<Half>> = vec![vec![]];
                for e in v {
                    let right = e.dnf(negated)?;
                    if out.len().saturating_mul(right.len()) > MAX_TERMS {
                        return Err(too_many());
                    }
                    out = out.iter().flat_map(|l| right.iter().map(move |r| [l.as_slice(), r].concat())).collect();
                }
                Ok(out)
            }
        }
    }
}

fn too_many() -> String {
    format!("expands to more than {MAX_TERMS} intersections (one block each)")
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Token {
    Half(u64, bool),
    Open,
    Close,
    Union,
    Not,
}

fn tokens(text: &str) -> Result<Vec<(Token, usize)>, String> {
    let bytes = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        let at = i + 1;
        match c {
            b' ' | b'\t' | b'\n' | b'\r' => i += 1,
            b'(' => {
                out.push((Token::Open, at));
                i += 1;
            }
            b')' => {
                out.push((Token::Close, at));
                i += 1;
            }
            b'|' => {
                out.push((Token::Union, at));
                i += 1;
            }
            b'~' => {
                out.push((Token::Not, at));
                i += 1;
            }
            b'+' | b'-' | b'0'..=b'9' => {
                let plus = c != b'-';
                let start = if c.is_ascii_digit() { i } else { i + 1 };
                let mut end = start;
                while end < bytes.len() && bytes[end].is_ascii_digit() {
                    end += 1;
                }
                let id = text[start..end]
                    .parse::<u64>()
                    .map_err(|_| format!("character {at}: a surface id must follow `{}`", c as char))?;
                out.push((Token::Half(id, plus), at));
                i = end;
            }
            _ => {
                let ch = text[i..].chars().next().unwrap_or('?');
                return Err(format!("character {at}: unexpected `{ch}`"));
            }
        }
    }
    Ok(out)
}

/// Parses a region expression.
pub fn parse(text: &str) -> Result<Expr, String> {
    parse_noting(text).map(|(e, _)| e)
}

/// Parses a region expression, and says whether OpenMC reads it otherwise:
/// OpenMC (0.15) removes a `~` by flipping the tokens inside its
/// parentheses before intersection binds tighter than union, so a group
/// under `~` that mixes intersection and union without parentheses of
/// its own, `~(1 2 | 3)`, means `−1 ∪ (−2 ∩ −3)` there, not the
/// documented `(−1 ∪ −2) ∩ −3` that this parser gives.
pub fn parse_noting(text: &str) -> Result<(Expr, bool), String> {
    let tokens = tokens(text)?;
    let mut p = Parser { tokens: &tokens, at: 0, len: text.len(), group_mixed: false, differs: false };
    let (e, _) = p.union()?;
    match p.tokens.get(p.at) {
        None => Ok((e, p.differs)),
        Some((Token::Close, at)) => Err(format!("character {at}: `)` without `(`")),
        Some((_, at)) => Err(format!("character {at}: unexpected token")),
    }
}

struct Parser<'a> {
    tokens: &'a [(Token, usize)],
    at: usize,
    len: usize,
    /// Whether the group just closed mixed intersection and union at its top.
    group_mixed: bool,
    /// Whether a `~` applies to such a group.
    differs: bool,
}

impl Parser<'_> {
    fn peek(&self) -> Option<Token> {
        self.tokens.get(self.at).map(|t| t.0)
    }

    fn place(&self) -> usize {
        self.tokens.get(self.at).map_or(self.len + 1, |t| t.1)
    }

    /// The union, and whether it mixes unions with intersections written
    /// without parentheses.
    fn union(&mut self) -> Result<(Expr, bool), String> {
        let (first, mut joined) = self.intersection()?;
        let mut v = vec![first];
        while self.peek() == Some(Token::Union) {
            self.at += 1;
            let (e, j) = self.intersection()?;
            joined |= j;
            v.push(e);
        }
        let mixed = v.len() > 1 && joined;
        Ok((if v.len() == 1 { v.remove(0) } else { Expr::Or(v) }, mixed))
    }

    /// The intersection, and whether it has more than one factor.
    fn intersection(&mut self) -> Result<(Expr, bool), String> {
        let mut v = vec![self.factor()?];
        while matches!(self.peek(), Some(Token::Half(..) | Token::Open | Token::Not)) {
            v.push(self.factor()?);
        }
        let joined = v.len() > 1;
        Ok((if v.len() == 1 { v.remove(0) } else { Expr::And(v) }, joined))
    }

    fn factor(&mut self) -> Result<Expr, String> {
        let place = self.place();
        match self.peek() {
            Some(Token::Half(s, plus)) => {
                self.at += 1;
                Ok(Expr::Half(s, plus))
            }
            Some(Token::Not) => {
                self.at += 1;
                let group = self.peek() == Some(Token::Open);
                let e = self.factor()?;
                self.differs |= group && self.group_mixed;
                Ok(Expr::Not(Box::new(e)))
            }
            Some(Token::Open) => {
                self.at += 1;
                let (e, mixed) = self.union()?;
                if self.peek() != Some(Token::Close) {
                    return Err(format!("character {place}: `(` is never closed"));
                }
                self.at += 1;
                self.group_mixed = mixed;
                Ok(e)
            }
            Some(Token::Union) => Err(format!("character {place}: `|` needs a region on each side")),
            Some(Token::Close) => Err(format!("character {place}: `)` where a region was expected")),
            None => Err(format!("character {place}: the expression ends where a region was expected")),
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn precedence() {
        let h = |s, p| Expr::Half(s, p);
        assert_eq!(parse("1 | 2 -3").unwrap(), Expr::Or(vec![h(1, true), Expr::And(vec![h(2, true), h(3, false)])]));
        assert_eq!(parse("~1 2").unwrap(), Expr::And(vec![Expr::Not(Box::new(h(1, true))), h(2, true)]));
        assert_eq!(parse("~(1 | +2)").unwrap(), Expr::Not(Box::new(Expr::Or(vec![h(1, true), h(2, true)]))));
        assert_eq!(parse("-1").unwrap(), h(1, false));
    }

    #[test]
    fn terms_push_complements_down() {
        // ~(1 | -2) 3 = -1 +2 +3
        assert_eq!(parse("~(1 | -2) 3").unwrap().terms().unwrap(), vec![vec![(1, false), (2, true), (3, true)]]);
        // ~(1 2) = -1 | -2
        assert_eq!(parse("~(1 2)").unwrap().terms().unwrap(), vec![vec![(1, false)], vec![(2, false)]]);
        // A term with both sides of a surface is empty.
        assert_eq!(parse("(1 | 2) -1").unwrap().terms().unwrap(), vec![vec![(1, false), (2, true)]]);
    }

    #[test]
    fn errors_name_the_character() {
        assert_eq!(parse("1 (2").unwrap_err(), "character 3: `(` is never closed");
        assert_eq!(parse("1 | ").unwrap_err(), "character 5: the expression ends where a region was expected");
        assert_eq!(parse("1 ) 2").unwrap_err(), "character 3: `)` without `(`");
        assert_eq!(parse("1 & 2").unwrap_err(), "character 3: unexpected `&`");
        assert_eq!(parse("1 -").unwrap_err(), "character 3: a surface id must follow `-`");
    }

    #[test]
    fn notes_where_openmc_reads_a_complement_otherwise() {
        assert!(parse_noting("~(1 2 | 3)").unwrap().1);
        assert!(parse_noting("4 ~(1 | 2 3)").unwrap().1);
        assert!(!parse_noting("~((1 2) | 3)").unwrap().1);
        assert!(!parse_noting("~(1 2) | 3").unwrap().1);
        assert!(!parse_noting("~(1 | 2) 3 | 4").unwrap().1);
        assert!(!parse_noting("(1 2 | 3)").unwrap().1);
    }

    #[test]
    fn too_many_terms() {
        let text = (0..13).map(|i| format!("({} | {})", 2 * i + 1, 2 * i + 2)).collect::<Vec<_>>().join(" ");
        assert!(parse(&text).unwrap().terms().unwrap_err().contains("more than 4096"));
    }
}
