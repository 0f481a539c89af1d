//! `weldseam eval` on the suites judged scene by scene against their right
//! answers (the fault suite, curved members, webs near the flange's edge,
//! blocks on a plate),
//! run as a script runs it: each counts its outcomes as within the bar,
//! refused or confident wrong, and keeps held-out rows apart.

use crate::cli::weldseam;

/// `eval --suite faults` judges every scene against its right answer: a
/// wrong joint requested must be refused, so no scene of that fault is
/// within the bar, and each is counted as refused or confident wrong.
#[test]
fn eval_counts_fault_scenes_as_within_the_bar_refused_or_confident_wrong() {
    let out = weldseam(&["eval", "--suite", "faults", "--filter", "wrong-joint-lap", "--limit", "2", "--robust-only"]);
    let text = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    // Only a confident wrong seam fails this suite; refusals are answers.
    assert!(out.status.success() || stderr.contains("got a confident wrong seam"), "{text}\n{stderr}");
    assert!(text.contains("2 scenes as raw frames"), "{text}");
    let rows: Vec<&str> = text.lines().filter(|l| l.starts_with("fault-wrong-joint-lap-")).collect();
    assert!(rows.len() >= 2, "{text}");
    for row in &rows[..2] {
        assert!(row.contains("-as-") && (row.ends_with("refused") || row.ends_with("confident wrong")), "{row}");
    }
    let per_fault = text
        .lines()
        .find(|l| l.starts_with("robust") && l.contains("wrong-joint"))
        .unwrap_or_else(|| panic!("no per-fault row in\n{text}"));
    let counts: Vec<&str> = per_fault.split_whitespace().skip(2).collect();
    assert_eq!(counts[..2], ["2", "0"], "two scenes, none within the bar: {per_fault}");
    assert!(text.contains("Confident wrong seams (robust)") && text.contains("Refusals (robust)"), "{text}");
}

/// `eval --suite curved` plans a curved member as `t_fillet` and `auto`
/// and counts each request's outcome in the tuning rows, held-out scenes
/// apart; no curved root is planned as a line.
#[test]
fn eval_of_curved_members_counts_refusals_per_request_and_keeps_held_out_rows_apart() {
    let out = weldseam(&["eval", "--suite", "curved", "--filter", "curved-wall-00", "--limit", "1"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}\n{}", String::from_utf8_lossy(&out.stderr));
    let rows: Vec<&str> = text.lines().filter(|l| l.starts_with("curved-wall-00")).collect();
    assert_eq!(rows.len(), 2, "one row per request: {text}");
    assert!(rows.iter().all(|r| r.contains("refused (right)")), "{text}");
    for request in ["t_fillet", "auto"] {
        let tally = text
            .lines()
            .find(|l| l.starts_with("tuning") && l.split_whitespace().nth(1) == Some(request))
            .unwrap_or_else(|| panic!("no tuning row for {request} in\n{text}"));
        let counts: Vec<&str> = tally.split_whitespace().skip(2).collect();
        assert_eq!(counts, ["1", "1", "0", "0"], "{tally}");
    }
    assert!(!text.lines().any(|l| l.starts_with("held out")), "the filter keeps no held-out scene: {text}");
}

/// `eval --suite web-near-edge` judges each root of a tee whose web
/// stands near the flange's edge, under `t_fillet` or, asked, `auto`,
/// summed per side of the web; it plans under no other request.
#[test]
fn eval_of_webs_near_the_flange_s_edge_judges_each_root() {
    let out = weldseam(&["eval", "--suite", "web-near-edge", "--filter", "web-edge-03", "--joint-request", "auto"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}\n{}", String::from_utf8_lossy(&out.stderr));
    for side in ["narrow", "wide"] {
        let tally = text
            .lines()
            .find(|l| l.starts_with("tuning") && l.contains(&format!("auto, {side} side's root")))
            .unwrap_or_else(|| panic!("no tuning row for the {side} side in\n{text}"));
        // Roots, right, refused, not named, confident wrong: one root, right.
        let counts: Vec<&str> = tally.split_whitespace().rev().take(5).collect();
        assert_eq!(counts, ["0", "0", "0", "1", "1"], "{tally}");
    }
    let lap = weldseam(&["eval", "--suite", "web-near-edge", "--joint-request", "lap", "--limit", "1"]);
    assert!(!lap.status.success(), "a lap request on tees is refused");
}

/// `eval --suite blocks` judges each root of a block on a plate, under
/// `t_fillet` or, asked, `auto`, summed per block and per seen or hidden
/// root; it plans under no other request.
#[test]
fn eval_of_blocks_on_a_plate_judges_each_root() {
    let out = weldseam(&["eval", "--suite", "blocks", "--filter", "blocks-01-"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}\n{}", String::from_utf8_lossy(&out.stderr));
    // Seen from over a corner: two roots seen, two hidden behind the block.
    let rows: Vec<&str> = text.lines().filter(|l| l.contains("block 1 ")).collect();
    assert_eq!(rows.len(), 4, "{text}");
    assert_eq!(rows.iter().filter(|r| r.contains("(seen)")).count(), 2, "{text}");
    for seen in ["seen", "hidden"] {
        let tally = text
            .lines()
            .find(|l| l.starts_with("tuning") && l.contains(&format!("t_fillet, on the plate, {seen}")))
            .unwrap_or_else(|| panic!("no tuning row for the {seen} roots in\n{text}"));
        // Confident wrong, not named, refused, right, roots (read from the
        // row's end): of the two seen, the +y root is planned from its
        // face, the -x one refused.
        let counts: Vec<&str> = tally.split_whitespace().rev().take(5).collect();
        let expected = if seen == "seen" { ["0", "0", "1", "1", "2"] } else { ["0", "0", "0", "2", "2"] };
        assert_eq!(counts, expected, "{tally}");
    }
    assert!(!text.lines().any(|l| l.starts_with("held out")), "the filter keeps no held-out scene: {text}");
    let lap = weldseam(&["eval", "--suite", "blocks", "--joint-request", "lap", "--limit", "1"]);
    assert!(!lap.status.success(), "a lap request on blocks is refused");
}
