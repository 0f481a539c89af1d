//! One table type for the subcommands that print tables (`eval` and
//! `bench`): text cells with a title and notes, printed as aligned text for
//! a terminal or as Markdown for the documents.

/// A table of text cells, printed as aligned text or as Markdown.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Table {
    pub title: String,
    pub headers: Vec<String>,
    pub rows: Vec<Vec<String>>,
    /// Sentences printed under the table.
    pub notes: Vec<String>,
}

impl Table {
    pub fn new(title: impl Into<String>, headers: &[&str]) -> Self {
        Table { title: title.into(), headers: headers.iter().map(|h| h.to_string()).collect(), ..Table::default() }
    }

    pub fn push(&mut self, row: Vec<String>) {
        self.rows.push(row);
    }

    /// Columns padded to their widest cell; the first left-aligned, the
    /// rest right-aligned.
    pub fn to_text(&self) -> String {
        let columns = self.headers.len().max(self.rows.iter().map(Vec::len).max().unwrap_or(0));
        let cell = |row: &[String], c: usize| row.get(c).map(String::as_str).unwrap_or("").to_string();
        let widths: Vec<usize> = (0..columns)
            .map(|c| {
                std::iter::once(&self.headers).chain(&self.rows).map(|r| cell(r, c).chars().count()).max().unwrap_or(0)
            })
            .collect();
        let line = |row: &[String]| {
            let cells: Vec<String> = (0..columns)
                .map(|c| {
                    let text = cell(row, c);
                    if c == 0 { format!("{text:<w$}", w = widths[c]) } else { format!("{text:>w$}", w = widths[c]) }
                })
                .collect();
            cells.join("  ").trim_end().to_string()
        };
        let mut out = format!("{}\n", self.title);
        out.push_str(&line(&self.headers));
        out.push('\n');
        let rule: Vec<String> = widths.iter().map(|w| "-".repeat(*w)).collect();
        out.push_str(&rule.join("  "));
        out.push('\n');
        for row in &self.rows {
            out.push_str(&line(row));
            out.push('\n');
        }
        for note in &self.notes {
            out.push_str(note);
            out.push('\n');
        }
        out
    }

    /// A Markdown heading-less table: the title in bold, then the table.
    pub fn to_markdown(&self) -> String {
        let escape = |s: &str| s.replace('|', "\\|");
        let row =
            |cells: &[String]| format!("| {} |\n", cells.iter().map(|c| escape(c)).collect::<Vec<_>>().join(" | "));
        let mut out = format!("**{}**\n\n", self.title);
        out.push_str(&row(&self.headers));
        let align: Vec<String> =
            (0..self.headers.len()).map(|c| if c == 0 { "---".into() } else { "---:".into() }).collect();
        out.push_str(&format!("| {} |\n", align.join(" | ")));
        for r in &self.rows {
            out.push_str(&row(r));
        }
        if !self.notes.is_empty() {
            out.push('\n');
            for note in &self.notes {
                out.push_str(note);
                out.push('\n');
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_align_text_and_escape_markdown() {
        let mut t = Table::new("T", &["name", "ms"]);
        t.push(vec!["a|b".into(), "1.0".into()]);
        t.push(vec!["longer".into(), "12.5".into()]);
        let text = t.to_text();
        assert!(text.contains("\na|b      1.0\n"), "{text}");
        assert!(text.contains("\nlonger  12.5\n"), "{text}");
        let md = t.to_markdown();
        assert!(md.contains("| a\\|b | 1.0 |"), "{md}");
        assert!(md.contains("| --- | ---: |"), "{md}");
    }
}
