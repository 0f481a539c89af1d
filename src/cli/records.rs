//! `weldseam records` and `weldseam replay`: the daemon's plan records
//! (`[records]`) listed, one exported (its frame as PCD, its request and
//! answer as JSON), and one planned again to see whether today's build
//! gives the same plan.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use weldseam::records::{self, Outcome, Record};

use super::args::ConfigArgs;
use super::table::Table;

#[derive(Debug, clap::Args)]
pub struct RecordsArgs {
    /// The records' directory; records.dir of the config otherwise.
    pub dir: Option<PathBuf>,
    #[command(flatten)]
    pub config: ConfigArgs,
    /// List only the newest this many records.
    #[arg(long, default_value_t = 50)]
    pub last: usize,
    /// Write record ID's frame to FILE as PCD (binary) and its request and
    /// answer beside it as JSON (FILE with the extension .json).
    #[arg(long, num_args = 2, value_names = ["ID", "FILE"])]
    pub export: Option<Vec<String>>,
}

#[derive(Debug, clap::Args)]
pub struct ReplayArgs {
    /// A record file (`<sequence>-r<request id>.wsrec`).
    pub record: PathBuf,
}

pub fn run(args: &RecordsArgs) -> anyhow::Result<()> {
    let dir = match &args.dir {
        Some(dir) => dir.clone(),
        None => {
            let config = args.config.load()?;
            match config.records.directory() {
                Some(dir) => dir.to_path_buf(),
                None => bail!("no directory given and records.dir of the config is empty"),
            }
        }
    };
    if let Some([id, file]) = args.export.as_deref() {
        return export(&dir, id, Path::new(file));
    }
    let entries = records::list(&dir)?;
    let mut table = Table::new(
        format!("{} plan records in {}", entries.len(), dir.display()),
        &["record", "time (UTC)", "link", "request", "camera", "frame", "points", "outcome", "rule", "config"],
    );
    let skip = entries.len().saturating_sub(args.last);
    for entry in &entries[skip..] {
        match records::read(&entry.path) {
            Ok(r) => table.push(vec![
                entry.id.clone(),
                utc(r.time_us),
                r.link.clone(),
                r.request_id.to_string(),
                r.camera.clone(),
                r.frame.frame_id.to_string(),
                r.points.len().to_string(),
                r.outcome.name().to_string(),
                match &r.outcome {
                    Outcome::Refused { rule: Some(rule), .. } => rule.clone(),
                    _ => String::new(),
                },
                r.config_hash.clone(),
            ]),
            Err(e) => table.push(vec![entry.id.clone(), format!("unreadable: {e}")]),
        }
    }
    if skip > 0 {
        table.notes.push(format!("{skip} older records not shown (--last)"));
    }
    std::io::stdout().lock().write_all(table.to_text().as_bytes())?;
    Ok(())
}

/// `YYYY-MM-DD hh:mm:ss` of microseconds since the Unix epoch.
fn utc(us: u64) -> String {
    let secs = us / 1_000_000;
    let (days, rest) = ((secs / 86_400) as i64, secs % 86_400);
    // Howard Hinnant's civil-from-days.
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02} {:02}:{:02}:{:02}", rest / 3600, rest / 60 % 60, rest % 60)
}

fn export(dir: &Path, id: &str, file: &Path) -> anyhow::Result<()> {
    let path = records::find(dir, id)?;
    let record = records::read(&path)?;
    let (cloud, _) = record.cloud()?;
    let out = std::fs::File::create(file).with_context(|| format!("cannot create {}", file.display()))?;
    weldseam::cloud::pcd::write_binary(&cloud, std::io::BufWriter::new(out))
        .with_context(|| format!("cannot write {}", file.display()))?;
    let json_path = file.with_extension("json");
    let json = serde_json::json!({
        "record": id,
        "time_us": record.time_us,
        "link": record.link,
        "request_id": record.request_id,
        "request": record.request,
        "frame": record.frame,
        "camera": record.camera,
        "config_hash": record.config_hash,
        "config": record.config_text,
        "procedure": record.procedure_text,
        "format": record.format,
        "outcome": outcome_json(&record.outcome)?,
    });
    std::fs::write(&json_path, serde_json::to_vec_pretty(&json)?)
        .with_context(|| format!("cannot write {}", json_path.display()))?;
    println!("record {id}: frame to {}, request and answer to {}", file.display(), json_path.display());
    Ok(())
}

/// The answer as the export writes it: a plan as `plan --json` prints
/// it, each seam with its figures along it and its process.
fn outcome_json(outcome: &Outcome) -> anyhow::Result<serde_json::Value> {
    Ok(match outcome {
        Outcome::Planned(result) => serde_json::json!({ "Planned": super::plan_json::plan_json(result) }),
        refused => serde_json::to_value(refused)?,
    })
}

/// Plans the record again; fails (exit 1) when the plan changed.
pub fn replay(args: &ReplayArgs) -> anyhow::Result<()> {
    let record: Record = records::read(&args.record)?;
    let replayed = records::replay::replay(&record)?;
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "record {}: request {} on frame {} from {} ({} points), recorded {}",
        args.record.display(),
        record.request_id,
        record.frame.frame_id,
        record.camera,
        record.points.len(),
        record.outcome.name()
    )?;
    if replayed.config_hash != record.config_hash {
        writeln!(
            out,
            "note: this build reads the recorded configuration as {} where the daemon had {}: a default changed",
            replayed.config_hash, record.config_hash
        )?;
    }
    if replayed.same() {
        writeln!(out, "the same plan, bit for bit ({})", replayed.outcome.name())?;
        return Ok(());
    }
    writeln!(out, "the plan CHANGED ({} now):", replayed.outcome.name())?;
    for change in &replayed.changes.listed {
        writeln!(out, "  {change}")?;
    }
    if replayed.changes.more > 0 {
        writeln!(out, "  ... and {} more", replayed.changes.more)?;
    }
    bail!("the replayed plan differs from the recorded one")
}
