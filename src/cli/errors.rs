//! How an error reaches the person at the terminal: one line, each cause
//! once. Library errors often carry their cause both in their own message
//! and as `source()` (an I/O error inside "cannot read FILE: ..."), and a
//! plain walk of the chain would print such a cause twice.

/// The error and its causes joined by `: `, leaving out a cause whose
/// text the message already holds.
pub fn render(error: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in error.chain() {
        let text = cause.to_string();
        if line.contains(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, thiserror::Error)]
    #[error("cannot read frame.pcd: {0}")]
    struct Repeats(#[source] std::io::Error);

    #[test]
    fn a_cause_already_in_the_message_is_printed_once() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "No such file or directory");
        let e = anyhow::Error::new(Repeats(io)).context("no seam found");
        assert_eq!(render(&e), "no seam found: cannot read frame.pcd: No such file or directory");
    }

    #[test]
    fn distinct_causes_are_all_kept() {
        let e = anyhow::anyhow!("the stage failed").context("no seam found in a.pcd");
        assert_eq!(render(&e), "no seam found in a.pcd: the stage failed");
    }
}
