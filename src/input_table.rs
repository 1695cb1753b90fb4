//! The known inputs of `obsan simulate MODEL.sys --inputs FILE.csv`: a
//! header `t,<input names>`, then rows increasing in `t`, the inputs linear
//! between rows; two rows at one `t` are a step (the value jumps there).
//! Every rejection names `file:line:column`.

use crate::Failure;

/// The most data rows of an inputs file: each is a breakpoint the
/// integrator stops at, so more would only be refused later as too many steps.
pub const MAX_INPUT_ROWS: usize = 1_000_000;

/// An inputs file, read and checked.
#[derive(Clone, Debug, PartialEq)]
pub struct InputTable {
    pub file: String,
    /// The input columns (after `t`), in file order.
    pub names: Vec<String>,
    /// The header's line and the column each name starts at, for messages.
    pub header_line: usize,
    pub name_cols: Vec<usize>,
    /// Times: non-decreasing, at most two rows at one time.
    pub t: Vec<f64>,
    /// `rows[k][c]`: column `c` at row `k`.
    pub rows: Vec<Vec<f64>>,
    /// The line of each row in the file (1-based), for messages.
    pub lines: Vec<usize>,
}

/// The fields of one line with the 1-based character column each starts at.
fn fields(line: &str) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut col = 1;
    for f in line.split(',') {
        let lead = f.chars().take_while(|c| c.is_whitespace()).count();
        out.push((col + lead, f.trim()));
        col += f.chars().count() + 1;
    }
    out
}

fn valid_name(s: &str) -> bool {
    let mut c = s.chars();
    c.next()
        .is_some_and(|f| f.is_ascii_alphabetic() || f == '_')
        && c.all(|x| x.is_ascii_alphanumeric() || x == '_')
}

/// Read an inputs file from its text (`file` names it in messages).
pub fn read_input_table(text: &str, file: &str) -> Result<InputTable, Failure> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let at = |line: usize, col: usize, m: &str| Failure(format!("{file}:{line}:{col}: {m}"));
    // `str::lines` ends lines at LF and drops a CR before it; a lone CR
    // (old Mac files) ends a line too.
    let mut lines = text
        .split('\n')
        .flat_map(|l| l.strip_suffix('\r').unwrap_or(l).split('\r'))
        .enumerate()
        .map(|(i, l)| (i + 1, l))
        .filter(|(_, l)| !(l.trim().is_empty() || l.trim_start().starts_with('#')));
    let Some((hline, header)) = lines.next() else {
        return Err(at(
            1,
            1,
            "the file is empty: expected a header t,<input names>",
        ));
    };
    let head = fields(header);
    if head[0].1 != "t" {
        return Err(at(
            hline,
            head[0].0,
            &format!("the first column must be 't', found '{}'", head[0].1),
        ));
    }
    let mut names: Vec<String> = Vec::new();
    for &(col, name) in &head[1..] {
        if !valid_name(name) {
            return Err(at(hline, col, &format!("'{name}' is not an input name")));
        }
        if name == "t" || names.iter().any(|n| n == name) {
            return Err(at(hline, col, &format!("column '{name}' appears twice")));
        }
        names.push(name.to_string());
    }
    if names.is_empty() {
        return Err(at(hline, 1, "no input column after 't'"));
    }
    let mut table = InputTable {
        file: file.to_string(),
        names,
        header_line: hline,
        name_cols: head[1..].iter().map(|f| f.0).collect(),
        t: Vec::new(),
        rows: Vec::new(),
        lines: Vec::new(),
    };
    for (line, body) in lines {
        if table.t.len() == MAX_INPUT_ROWS {
            return Err(at(
                line,
                1,
                &format!("more than {MAX_INPUT_ROWS} rows (obsan's limit)"),
            ));
        }
        let f = fields(body);
        if f.len() != head.len() {
            let col = f.get(head.len()).map_or(body.chars().count() + 1, |x| x.0);
            return Err(at(
                line,
                col,
                &format!("{} fields, the header has {}", f.len(), head.len()),
            ));
        }
        let mut row = Vec::with_capacity(f.len() - 1);
        for (j, &(col, cell)) in f.iter().enumerate() {
            let v = cell
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    let what = if j == 0 { "t" } else { &table.names[j - 1] };
                    at(
                        line,
                        col,
                        &format!("{what} '{cell}' is not a finite number"),
                    )
                })?;
            row.push(v);
        }
        let t = row.remove(0);
        let n = table.t.len();
        if n > 0 && t < table.t[n - 1] {
            return Err(at(
                line,
                f[0].0,
                &format!("t {t} is before the previous row's {}", table.t[n - 1]),
            ));
        }
        if n > 1 && t == table.t[n - 2] {
            return Err(at(
                line,
                f[0].0,
                &format!("a third row at t {t}: a step is two rows at one time (before, after)"),
            ));
        }
        table.t.push(t);
        table.rows.push(row);
        table.lines.push(line);
    }
    if table.t.is_empty() {
        return Err(at(hline, 1, "no rows after the header"));
    }
    Ok(table)
}

impl InputTable {
    /// On `[t0, t1]` (inside one piece, `t0 < t1`): per column, the value at
    /// `t0` and the slope, the piece starting at the last row at or before
    /// `t0` (after a step: its second row).
    pub fn piece(&self, t0: f64, t1: f64) -> Vec<(f64, f64)> {
        let r = self.t.partition_point(|&t| t <= t0).saturating_sub(1);
        let r = r.min(self.t.len().saturating_sub(2));
        if self.t.len() < 2 || self.t[r + 1] <= self.t[r] {
            return self.rows[r].iter().map(|&v| (v, 0.0)).collect();
        }
        debug_assert!(t1 <= self.t[r + 1]);
        let h = self.t[r + 1] - self.t[r];
        self.rows[r]
            .iter()
            .zip(&self.rows[r + 1])
            .map(|(&a, &b)| {
                let slope = (b - a) / h;
                (a + slope * (t0 - self.t[r]), slope)
            })
            .collect()
    }

    /// A located refusal unless the rows cover `[0, until]`.
    pub fn check_covers(&self, until: f64) -> Result<(), Failure> {
        let (first, last) = (self.t[0], self.t[self.t.len() - 1]);
        let (l0, l1) = (self.lines[0], self.lines[self.lines.len() - 1]);
        if first > 0.0 {
            return Err(Failure(format!(
                "{}:{l0}:1: the inputs start at t {first}: the simulation starts at 0",
                self.file
            )));
        }
        if last < until {
            return Err(Failure(format!(
                "{}:{l1}:1: the inputs end at t {last}: --until {until} needs them up to {until}",
                self.file
            )));
        }
        Ok(())
    }

    /// The distinct row times strictly inside `(0, until)`: where the
    /// integrator must stop so that a kink or a step is not smeared.
    pub fn breakpoints(&self, until: f64) -> Vec<f64> {
        let mut b: Vec<f64> = self
            .t
            .iter()
            .copied()
            .filter(|&t| t > 0.0 && t < until)
            .collect();
        b.dedup();
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        read_input_table(text, "u.csv").unwrap_err().0
    }

    #[test]
    fn reads_rows_steps_comments_and_line_ends() {
        let t = read_input_table(
            "\u{feff}# dosing\nt, u ,w\r\n0,1,2\n\n1,1,2\r1,3,4\n",
            "u.csv",
        )
        .unwrap();
        assert_eq!(t.names, ["u", "w"]);
        assert_eq!(t.t, [0.0, 1.0, 1.0]);
        assert_eq!(t.rows[2], [3.0, 4.0]);
        assert_eq!(t.lines, [3, 5, 6]);
    }

    #[test]
    fn every_error_names_line_and_column() {
        assert_eq!(
            err(""),
            "u.csv:1:1: the file is empty: expected a header t,<input names>"
        );
        assert!(err("time,u\n").starts_with("u.csv:1:1: the first column must be 't'"));
        assert!(err("t,u,u\n").starts_with("u.csv:1:5: column 'u' appears twice"));
        assert!(err("t,2u\n").starts_with("u.csv:1:3: '2u' is not an input name"));
        assert!(err("t,u\n0,1\n1, x\n").starts_with("u.csv:3:4: u 'x' is not a finite number"));
        assert!(err("t,u\n0,inf\n").starts_with("u.csv:2:3: u 'inf'"));
        assert!(err("t,u\n0,1,2\n").starts_with("u.csv:2:5: 3 fields, the header has 2"));
        assert!(err("t,u\n0\n").starts_with("u.csv:2:2: 1 fields"));
        assert!(err("t,u\n1,1\n0.5,1\n").starts_with("u.csv:3:1: t 0.5 is before"));
        assert!(err("t,u\n1,1\n1,2\n1,3\n").starts_with("u.csv:4:1: a third row"));
        assert!(err("t,u\n").starts_with("u.csv:1:1: no rows"));
    }

    #[test]
    fn pieces_are_linear_and_steps_jump() {
        let t = read_input_table("t,u\n0,0\n2,4\n2,10\n4,10\n", "u.csv").unwrap();
        // u = 2 t on [0, 2): at 0.5 the value 1, slope 2.
        assert_eq!(t.piece(0.5, 1.0), [(1.0, 2.0)]);
        // After the step at 2 the second row holds: 10, flat.
        assert_eq!(t.piece(2.0, 3.0), [(10.0, 0.0)]);
        assert_eq!(t.breakpoints(4.0), [2.0]);
        assert!(t.check_covers(4.0).is_ok());
        assert!(t.check_covers(5.0).unwrap_err().0.starts_with("u.csv:5:1:"));
    }

    /// Random byte edits of valid files: the reader never panics, and every
    /// rejection starts with `file:line:column:` inside the text.
    #[test]
    fn mutated_files_never_panic_and_are_located() {
        let seeds = [
            "t,u,w\n0,1,2\n1,1.5,-2\n1,3,4e1\n# c\n2,3,4\n",
            "t,u\r\n0,1\r\n",
        ];
        let alphabet = b"t,u0123456789.-e#\n\r \"x\xff";
        let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for _ in 0..20_000 {
            let seed = seeds[(next() % 2) as usize];
            let mut b = seed.as_bytes().to_vec();
            for _ in 0..(next() % 4 + 1) {
                let i = (next() as usize) % (b.len() + 1);
                let c = alphabet[(next() as usize) % alphabet.len()];
                match next() % 3 {
                    0 if i < b.len() => b[i] = c,
                    1 if i < b.len() => {
                        b.remove(i);
                    }
                    _ => b.insert(i, c),
                }
            }
            let text = String::from_utf8_lossy(&b);
            let n_lines = text.split(['\n', '\r']).count();
            if let Err(Failure(m)) = read_input_table(&text, "f.csv") {
                let rest = m.strip_prefix("f.csv:").expect("names the file");
                let mut parts = rest.splitn(3, ':');
                let line: usize = parts.next().unwrap().parse().expect("a line");
                let col: usize = parts.next().unwrap().parse().expect("a column");
                assert!(line >= 1 && line <= n_lines && col >= 1, "{m}");
            }
        }
    }
}
