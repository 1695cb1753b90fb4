//! Physical units as products of named bases with integer exponents
//! (`m`, `rad/s`, `m/s^2`, `1`), read from `unit NAME = UNIT` statements of
//! an effects file (docs/effects-format.md, Units) and computed by
//! obsan-diagnose's dimensional analysis of effects.
//!
//! A base is any unit symbol the user writes (`m`, `s`, `rad`, `deg`...);
//! obsan knows only `s` (time: delays, rates, the session clock) and `rad`
//! (what `atan`/`atan2` return). A column whose unit nobody declared is the
//! opaque base `[y]`: "the unit of y's column", which cancels like any base
//! (`[u]*s / ([u]*s)` is dimensionless) but is never replaced by a guess.

use std::collections::BTreeMap;
use std::fmt;

/// Exponents past this are refused (a unit such as `m^999` is a typo).
pub const MAX_UNIT_EXPONENT: i32 = 12;

/// A product of bases with nonzero integer exponents; empty: dimensionless.
#[derive(Clone, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Unit(BTreeMap<String, i32>);

/// One `unit NAME = UNIT` declaration of an effects file.
#[derive(Clone, Debug, PartialEq)]
pub struct UnitDecl {
    pub name: String,
    pub unit: Unit,
    /// 1-based line and column of the name in the file.
    pub line: usize,
    pub col: usize,
}

impl Unit {
    /// Dimensionless.
    pub fn one() -> Unit {
        Unit::default()
    }

    /// One base to the first power: `Unit::base("s")`.
    pub fn base(name: &str) -> Unit {
        Unit(BTreeMap::from([(name.to_string(), 1)]))
    }

    /// The opaque unit of a data column: `[y]`.
    pub fn column(name: &str) -> Unit {
        Unit::base(&format!("[{name}]"))
    }

    pub fn is_one(&self) -> bool {
        self.0.is_empty()
    }

    /// Whether it is exactly `base` to the first power.
    pub fn is(&self, base: &str) -> bool {
        self.0.len() == 1 && self.0.get(base) == Some(&1)
    }

    /// The columns (`[y]` bases) it names, without brackets.
    pub fn columns(&self) -> Vec<&str> {
        self.0
            .keys()
            .filter_map(|k| k.strip_prefix('[').and_then(|k| k.strip_suffix(']')))
            .collect()
    }

    /// `self * other^p`; `None` when an exponent would pass the cap.
    pub fn times_pow(&self, other: &Unit, p: i32) -> Option<Unit> {
        let mut m = self.0.clone();
        for (b, e) in &other.0 {
            let x = m
                .get(b)
                .copied()
                .unwrap_or(0)
                .checked_add(e.checked_mul(p)?)?;
            if x.abs() > MAX_UNIT_EXPONENT {
                return None;
            }
            if x == 0 {
                m.remove(b);
            } else {
                m.insert(b.clone(), x);
            }
        }
        Some(Unit(m))
    }

    /// `self^p`, or `self^(1/q)` with `root`: `None` when an exponent is not
    /// divisible or passes the cap.
    pub fn pow(&self, p: i32, root: i32) -> Option<Unit> {
        let mut m = BTreeMap::new();
        for (b, e) in &self.0 {
            let x = e.checked_mul(p)?;
            if root == 0 || x % root != 0 || (x / root).abs() > MAX_UNIT_EXPONENT {
                return None;
            }
            m.insert(b.clone(), x / root);
        }
        Some(Unit(m))
    }

    /// Read `m`, `rad/s`, `m/s^2`, `kg*m^2/s^2`, `1`, `1/s`: factors
    /// `NAME[^INT]` (or `1`) joined by `*` and `/`, each `/` dividing by the
    /// one factor after it. Errors give the byte offset in `text` where the
    /// reading stopped.
    pub fn parse(text: &str) -> Result<Unit, (usize, String)> {
        let b = text.as_bytes();
        let mut i = 0;
        let mut out = Unit::one();
        let mut sign = 1;
        let skip = |i: &mut usize| {
            while *i < b.len() && b[*i] == b' ' {
                *i += 1;
            }
        };
        loop {
            skip(&mut i);
            let start = i;
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                i += 1;
            }
            let word = &text[start..i];
            let factor = if word == "1" {
                Unit::one()
            } else if word.starts_with(|c: char| c.is_ascii_alphabetic()) {
                Unit::base(word)
            } else {
                return Err((
                    start,
                    "expected a unit symbol such as m, s, rad (or 1)".into(),
                ));
            };
            skip(&mut i);
            let mut p = 1;
            if i < b.len() && b[i] == b'^' {
                i += 1;
                skip(&mut i);
                let s = i;
                if i < b.len() && b[i] == b'-' {
                    i += 1;
                }
                while i < b.len() && b[i].is_ascii_digit() {
                    i += 1;
                }
                p = match text[s..i].parse::<i32>() {
                    Ok(p) if p != 0 && p.abs() <= MAX_UNIT_EXPONENT => p,
                    _ => {
                        return Err((
                            s,
                            format!(
                                "expected a nonzero integer exponent of at most {MAX_UNIT_EXPONENT}"
                            ),
                        ))
                    }
                };
                skip(&mut i);
            }
            out = out
                .times_pow(&factor, sign * p)
                .ok_or((start, format!("an exponent past {MAX_UNIT_EXPONENT}")))?;
            match b.get(i) {
                None => return Ok(out),
                Some(b'*') => sign = 1,
                Some(b'/') => sign = -1,
                Some(_) => return Err((i, "expected '*', '/' or the end of the unit".into())),
            }
            i += 1;
        }
    }
}

impl fmt::Display for Unit {
    /// `rad/s`, `1/s`, `m*s`, `s/rad`, `1` for dimensionless; `[y]` for a
    /// column's own unit.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let part = |pos: bool| -> Vec<String> {
            self.0
                .iter()
                .filter(|(_, e)| (**e > 0) == pos)
                .map(|(b, e)| match e.abs() {
                    1 => b.clone(),
                    k => format!("{b}^{k}"),
                })
                .collect()
        };
        let (num, den) = (part(true), part(false));
        let num = if num.is_empty() {
            "1".to_string()
        } else {
            num.join("*")
        };
        match den.len() {
            0 => write!(f, "{num}"),
            1 => write!(f, "{num}/{}", den[0]),
            _ => write!(f, "{num}/({})", den.join("*")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_read_and_print_back() {
        for (text, shown) in [
            ("m", "m"),
            ("rad/s", "rad/s"),
            ("m/s^2", "m/s^2"),
            ("kg*m^2/s^2", "kg*m^2/s^2"),
            ("1", "1"),
            ("1/s", "1/s"),
            ("s^-1", "1/s"),
            ("m / s / s", "m/s^2"),
            ("m*s/m", "s"),
            ("rad/m/s", "rad/(m*s)"),
        ] {
            assert_eq!(Unit::parse(text).map(|u| u.to_string()), Ok(shown.into()));
        }
        for (text, at) in [
            ("", 0),
            ("m/", 2),
            ("m^0", 2),
            ("m^x", 2),
            ("m s", 2),
            ("2", 0),
        ] {
            assert_eq!(Unit::parse(text).map_err(|e| e.0), Err(at), "{text}");
        }
    }

    #[test]
    fn opaque_columns_cancel_and_roots_need_even_exponents() {
        let u = Unit::column("u");
        let us = u.times_pow(&Unit::base("s"), 1).unwrap();
        assert_eq!(u.times_pow(&us, -1).unwrap().to_string(), "1/s");
        assert_eq!(us.columns(), vec!["u"]);
        assert_eq!(u.pow(2, 1).unwrap().pow(1, 2), Some(u.clone()));
        assert_eq!(u.pow(1, 2), None);
    }
}
