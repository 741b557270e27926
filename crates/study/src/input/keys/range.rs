//! The registry's range texts (`> 0`, `(-1, 0.5)`, `1 to 100000`, `` `auto`, `dense` ``) in a
//! typed form, so that the validator checks a value against the same range the doc prints.
//! Every range text of the registry must parse (a unit test reads them all), so a range the
//! validator cannot check cannot be written.

use std::fmt;

/// One end of a numeric range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Limit {
    /// The value may not equal it.
    Open(f64),
    /// The value may equal it.
    Closed(f64),
    /// Below another key of the same table (`[0, `d_outer`)`): a rule between two keys, which
    /// the validator checks by hand; the generic check ignores this end.
    BelowKey(&'static str),
}

/// The values a key may take.
#[derive(Clone, Debug, PartialEq)]
pub enum Range {
    /// Any value of its type (no range text).
    Any,
    /// A number between two limits, either of which may be absent (`> 0`, `[0, 1]`,
    /// `1 to 100000`).
    Between { lower: Option<Limit>, upper: Option<Limit> },
    /// One of these numbers (`3, 6`).
    Numbers(Vec<f64>),
    /// One of these names (`` `rectangle`, `circle` ``, `` `"auto"`, `"double"` ``).
    Names(Vec<&'static str>),
}

/// `x` as messages write it: plainly (`0.5`, `-70000000000`), or with an exponent when that is
/// shorter to read (`1e-14`).
pub fn number_text(x: f64) -> String {
    if x != 0.0 && (x.abs() < 1e-4 || x.abs() >= 1e15) {
        format!("{x:e}")
    } else {
        x.to_string()
    }
}

/// A range text the parser does not read.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("cannot read the range `{0}`")]
pub struct RangeError(pub &'static str);

fn number(text: &str) -> Option<f64> {
    text.trim().parse::<f64>().ok().filter(|x| x.is_finite())
}

/// A name in backticks, with or without double quotes inside (`` `auto` ``, `` `"auto"` ``).
fn name(text: &'static str) -> Option<&'static str> {
    let inner = text.trim().strip_prefix('`')?.strip_suffix('`')?;
    let inner = inner
        .strip_prefix('"')
        .and_then(|s| s.strip_suffix('"'))
        .unwrap_or(inner);
    (!inner.is_empty() && !inner.contains(['`', '"', ' '])).then_some(inner)
}

/// `(a, b)`, `[a, b]`, `(a, b]`, `[a, b)`; `b` may be another key in backticks.
fn interval(text: &'static str) -> Option<Range> {
    let open_low = match text.chars().next()? {
        '(' => true,
        '[' => false,
        _ => return None,
    };
    let open_high = match text.chars().last()? {
        ')' => true,
        ']' => false,
        _ => return None,
    };
    let (low, high) = text[1..text.len() - 1].split_once(',')?;
    let low = number(low)?;
    let lower = if open_low { Limit::Open(low) } else { Limit::Closed(low) };
    let upper = match (number(high), name(high)) {
        (Some(h), _) if open_high => Limit::Open(h),
        (Some(h), _) => Limit::Closed(h),
        (None, Some(key)) if open_high => Limit::BelowKey(key),
        _ => return None,
    };
    Some(Range::Between {
        lower: Some(lower),
        upper: Some(upper),
    })
}

impl Range {
    /// The typed form of a registry range text.
    pub fn parse(text: &'static str) -> Result<Range, RangeError> {
        let t = text.trim();
        let parsed = if t.is_empty() {
            Some(Range::Any)
        } else if let Some(x) = t.strip_prefix(">=") {
            number(x).map(|x| Range::Between {
                lower: Some(Limit::Closed(x)),
                upper: None,
            })
        } else if let Some(x) = t.strip_prefix('>') {
            number(x).map(|x| Range::Between {
                lower: Some(Limit::Open(x)),
                upper: None,
            })
        } else if let Some((a, b)) = t.split_once(" to ") {
            number(a).zip(number(b)).map(|(a, b)| Range::Between {
                lower: Some(Limit::Closed(a)),
                upper: Some(Limit::Closed(b)),
            })
        } else if t.starts_with(['(', '[']) {
            interval(t)
        } else if t.starts_with('`') {
            t.split(", ").map(name).collect::<Option<Vec<_>>>().map(Range::Names)
        } else {
            t.split(", ")
                .map(number)
                .collect::<Option<Vec<_>>>()
                .map(Range::Numbers)
        };
        parsed.ok_or(RangeError(text))
    }

    /// Whether the number `x` is in the range (a finite number, for a numeric range; a rule
    /// on another key is not checked here).
    pub fn admits(&self, x: f64) -> bool {
        let above = |l: &Option<Limit>| match l {
            Some(Limit::Open(a)) => x > *a,
            Some(Limit::Closed(a)) => x >= *a,
            _ => true,
        };
        let below = |l: &Option<Limit>| match l {
            Some(Limit::Open(b)) => x < *b,
            Some(Limit::Closed(b)) => x <= *b,
            _ => true,
        };
        match self {
            Range::Any | Range::Names(_) => true,
            Range::Between { lower, upper } => x.is_finite() && above(lower) && below(upper),
            Range::Numbers(values) => values.contains(&x),
        }
    }

    /// The names of a choice (empty for a numeric range).
    pub fn names(&self) -> &[&'static str] {
        match self {
            Range::Names(n) => n,
            _ => &[],
        }
    }
}

/// What a value out of the range must be, as the messages say it ("must be positive and
/// finite", "must lie in (-1, 0.5)").
impl fmt::Display for Range {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let limit = |l: &Limit| match l {
            Limit::Open(x) | Limit::Closed(x) => number_text(*x),
            Limit::BelowKey(k) => k.to_string(),
        };
        match self {
            Range::Any => write!(f, "may be any value"),
            Range::Between {
                lower: Some(Limit::Open(a)),
                upper: None | Some(Limit::BelowKey(_)),
            } if *a == 0.0 => write!(f, "must be positive and finite"),
            Range::Between {
                lower: Some(Limit::Closed(a)),
                upper: None | Some(Limit::BelowKey(_)),
            } if *a == 0.0 => write!(f, "must be non-negative and finite"),
            Range::Between {
                lower: Some(Limit::Closed(a)),
                upper: None | Some(Limit::BelowKey(_)),
            } => write!(f, "must be at least {}", number_text(*a)),
            Range::Between {
                lower: Some(Limit::Open(a)),
                upper: None | Some(Limit::BelowKey(_)),
            } => write!(f, "must be finite and > {}", number_text(*a)),
            Range::Between { lower, upper } => {
                let open = match lower {
                    Some(Limit::Open(_)) => "(",
                    _ => "[",
                };
                let close = match upper {
                    Some(Limit::Open(_)) => ")",
                    _ => "]",
                };
                let low = lower.as_ref().map_or("-inf".to_string(), limit);
                let high = upper.as_ref().map_or("inf".to_string(), limit);
                write!(f, "must lie in {open}{low}, {high}{close}")
            }
            Range::Numbers(values) => {
                let v: Vec<String> = values.iter().map(|x| number_text(*x)).collect();
                write!(f, "must be one of {}", v.join(", "))
            }
            Range::Names(names) => write!(f, "must be one of {}", names.join(", ")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_forms_of_the_registry_parse_and_check() {
        let positive = Range::parse("> 0").unwrap();
        assert!(positive.admits(1e-300) && !positive.admits(0.0) && !positive.admits(f64::INFINITY));
        assert_eq!(positive.to_string(), "must be positive and finite");
        let nu = Range::parse("(-1, 0.5)").unwrap();
        assert!(nu.admits(0.3) && !nu.admits(0.5) && !nu.admits(-1.0));
        assert_eq!(nu.to_string(), "must lie in (-1, 0.5)");
        let count = Range::parse("1 to 100000").unwrap();
        assert!(count.admits(1.0) && count.admits(100000.0) && !count.admits(0.0));
        assert_eq!(count.to_string(), "must lie in [1, 100000]");
        let tol = Range::parse("[1e-14, 1)").unwrap();
        assert!(tol.admits(1e-14) && !tol.admits(1.0));
        assert_eq!(tol.to_string(), "must lie in [1e-14, 1)");
        let inner = Range::parse("[0, `d_outer`)").unwrap();
        assert!(inner.admits(1e9) && !inner.admits(-1.0));
        assert_eq!(inner.to_string(), "must be non-negative and finite");
        assert_eq!(Range::parse("3, 6").unwrap(), Range::Numbers(vec![3.0, 6.0]));
        assert_eq!(
            Range::parse(r#"`"auto"`, `"double"`"#).unwrap().names(),
            ["auto", "double"]
        );
        assert_eq!(Range::parse(">= 1").unwrap().to_string(), "must be at least 1");
    }

    #[test]
    fn a_range_in_words_is_refused() {
        for text in ["at most 2,000,000 cells in all", "`a`, or a list", "(0, x)", "> zero"] {
            assert_eq!(Range::parse(text), Err(RangeError(text)), "{text}");
        }
    }
}
