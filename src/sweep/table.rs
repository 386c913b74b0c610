//! The table of a sweep: a CSV file (one row per run) after a few `#` comment lines that
//! say which sweep and which shard it is, and the merge of shards.
//!
//! ```text
//! # ricochet sweep 1
//! # version 0.1.0
//! # scene 5f1c09a2 bouncing_ball
//! # param e=0.2:0.8:0.3
//! # param t_end=0.6,1
//! # runs 6
//! # shard 0/1
//! run,e,t_end,stop,impacts,delta_e,…
//! 0,0.2,0.6,t_end,1,…
//! ```
//!
//! The comment lines identify the sweep: the format, ricochet's version, the CRC-32 of the
//! scene file's text and the scene's name, the parameters (canonical: equal values print
//! alike), the number of runs of the whole grid; and the shard. Readers that know `#`
//! comments skip them (`pandas.read_csv(f, comment="#")`, `polars.read_csv(f,
//! comment_prefix="#")`). Fields are quoted only when they must be (RFC 4180). A sweep
//! that was interrupted writes the rows of the runs that finished under one more line,
//! `# incomplete 3 of 4 runs finished: interrupted by SIGTERM`, which [`merge`] refuses
//! (and readers of format 1 before it, which know no such line).

use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::io::{BufRead, Write};

use crate::scene::Scene;

use super::SweepError;
use super::grid::{Grid, Shard};

/// The version of the table format (the first comment line).
pub const FORMAT: u32 = 1;

/// The comment lines of a table.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Header {
    /// ricochet's version that ran the sweep.
    pub version: String,
    /// The scene's name.
    pub scene: String,
    /// CRC-32 of the scene file's text.
    pub scene_crc32: u32,
    /// The parameters in canonical form, in the grid's order.
    pub params: Vec<String>,
    /// The number of runs of the whole grid.
    pub runs: usize,
    /// The share of the grid in this table.
    pub shard: Shard,
    /// Set when the table holds only the runs that finished before the sweep was
    /// interrupted: how many of the shard's runs and why (`# incomplete 3 of 4 runs
    /// finished: interrupted by SIGTERM`). [`merge`] refuses such a table. `None` for a
    /// complete table, whose header has no such line.
    pub incomplete: Option<String>,
}

impl Header {
    /// The header of `shard` of the sweep of `grid` over `scene`, by this version of
    /// ricochet.
    pub fn new(scene: &Scene, grid: &Grid, shard: Shard) -> Header {
        Header {
            version: env!("CARGO_PKG_VERSION").to_owned(),
            scene: scene.name.clone(),
            scene_crc32: crc32fast::hash(scene.text.as_bytes()),
            params: grid.params().iter().map(|p| p.canonical()).collect(),
            runs: grid.len(),
            shard,
            incomplete: None,
        }
    }

    /// The comment lines, each ending with `\n`.
    pub fn render(&self) -> String {
        let mut s = String::new();
        // Writing to a String cannot fail.
        let _ = writeln!(s, "# ricochet sweep {FORMAT}");
        let _ = writeln!(s, "# version {}", self.version);
        let _ = writeln!(s, "# scene {:08x} {}", self.scene_crc32, self.scene);
        for p in &self.params {
            let _ = writeln!(s, "# param {p}");
        }
        let _ = writeln!(s, "# runs {}", self.runs);
        let _ = writeln!(s, "# shard {}", self.shard);
        if let Some(why) = &self.incomplete {
            let _ = writeln!(s, "# incomplete {why}");
        }
        s
    }

    /// Parses the comment lines of `file` (its name, for errors).
    fn parse(lines: &[String], file: &str) -> Result<Header, SweepError> {
        let bad = |line: &str, reason: &str| SweepError::Format {
            file: file.to_owned(),
            reason: format!("{reason}: `{line}`"),
        };
        let mut it = lines.iter().map(|l| l.trim_end_matches(['\r', '\n']));
        let first = it.next().unwrap_or("");
        if first != format!("# ricochet sweep {FORMAT}") {
            return Err(bad(
                first,
                &format!("not a ricochet sweep table (format {FORMAT}): the first line is"),
            ));
        }
        let mut version = None;
        let mut scene = None;
        let mut params = Vec::new();
        let mut runs = None;
        let mut shard = None;
        let mut incomplete = None;
        for line in it {
            let body = line
                .strip_prefix("# ")
                .ok_or_else(|| bad(line, "a bad header line"))?;
            let (key, value) = body.split_once(' ').unwrap_or((body, ""));
            match key {
                "version" => version = Some(value.to_owned()),
                "scene" => {
                    let (crc, name) = value.split_once(' ').unwrap_or((value, ""));
                    let crc = u32::from_str_radix(crc, 16)
                        .map_err(|_| bad(line, "a bad scene checksum"))?;
                    scene = Some((crc, name.to_owned()));
                }
                "param" => params.push(value.to_owned()),
                "runs" => {
                    runs = Some(
                        value
                            .parse()
                            .map_err(|_| bad(line, "a bad number of runs"))?,
                    )
                }
                "shard" => {
                    shard = Some(
                        value
                            .parse::<Shard>()
                            .map_err(|e| bad(line, &e.to_string()))?,
                    )
                }
                "incomplete" => incomplete = Some(value.to_owned()),
                _ => return Err(bad(line, "an unknown header line")),
            }
        }
        let missing = |what: &str| SweepError::Format {
            file: file.to_owned(),
            reason: format!("the header has no `# {what}` line"),
        };
        let (scene_crc32, scene) = scene.ok_or_else(|| missing("scene"))?;
        Ok(Header {
            version: version.ok_or_else(|| missing("version"))?,
            scene,
            scene_crc32,
            params,
            runs: runs.ok_or_else(|| missing("runs"))?,
            shard: shard.ok_or_else(|| missing("shard"))?,
            incomplete,
        })
    }
}

/// Writes a table: the header's comment lines, the column names, then the records (the
/// fields of each row in the order of the columns).
pub fn write_table<W, R, F>(
    out: W,
    header: &Header,
    columns: &[String],
    records: impl IntoIterator<Item = R>,
) -> Result<(), SweepError>
where
    W: Write,
    R: IntoIterator<Item = F>,
    F: AsRef<[u8]>,
{
    let mut out = out;
    out.write_all(header.render().as_bytes())?;
    let mut w = csv::Writer::from_writer(out);
    w.write_record(columns)?;
    for r in records {
        w.write_record(r)?;
    }
    w.flush()?;
    Ok(())
}

/// A table read back: its header, columns and rows (with their run index).
#[derive(Clone, Debug)]
pub struct Table {
    /// The file's name (for errors).
    pub file: String,
    /// The comment lines.
    pub header: Header,
    /// The column names.
    pub columns: csv::StringRecord,
    /// The rows with their run index (the first field), in the file's order.
    pub rows: Vec<(usize, csv::StringRecord)>,
}

/// Reads a table written by [`write_table`] from `input` (`file`: its name, for errors).
pub fn read_table(mut input: impl BufRead, file: &str) -> Result<Table, SweepError> {
    let format = |reason: String| SweepError::Format {
        file: file.to_owned(),
        reason,
    };
    let mut lines = Vec::new();
    while input.fill_buf()?.first() == Some(&b'#') {
        let mut line = String::new();
        input.read_line(&mut line)?;
        lines.push(line);
    }
    let header = Header::parse(&lines, file)?;
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .from_reader(input);
    let columns = reader.headers()?.clone();
    if columns.get(0) != Some("run") {
        return Err(format("the first column is not `run`".to_owned()));
    }
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record?;
        let index: usize = record
            .get(0)
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| format(format!("a row without a run index: {record:?}")))?;
        rows.push((index, record));
    }
    Ok(Table {
        file: file.to_owned(),
        header,
        columns,
        rows,
    })
}

/// Joins the shards of one sweep into the whole table, rows by run index, under the
/// header of the whole grid (shard `0/1`): the result is byte for byte the table of the
/// sweep run unsharded. Errors: no input, tables of different sweeps (format, version,
/// scene, parameters, runs, columns), a table marked incomplete (an interrupted shard), a
/// row outside its table's shard, a run index that appears twice, runs missing.
pub fn merge(
    tables: Vec<Table>,
) -> Result<(Header, Vec<String>, Vec<csv::StringRecord>), SweepError> {
    let first = tables.first().ok_or(SweepError::NoShards)?;
    if let Some(t) = tables.iter().find(|t| t.header.incomplete.is_some()) {
        return Err(SweepError::Incomplete {
            file: t.file.clone(),
            why: t.header.incomplete.clone().unwrap_or_default(),
        });
    }
    let reference = first.header.clone();
    let columns = first.columns.clone();
    for t in &tables[1..] {
        let h = &t.header;
        let differs = |what: &str, a: String, b: String| SweepError::Mismatch {
            file: t.file.clone(),
            other: first.file.clone(),
            what: what.to_owned(),
            got: b,
            expected: a,
        };
        if h.version != reference.version {
            return Err(differs(
                "version",
                reference.version.clone(),
                h.version.clone(),
            ));
        }
        if (h.scene_crc32, &h.scene) != (reference.scene_crc32, &reference.scene) {
            return Err(differs(
                "scene",
                format!("{} (crc32 {:08x})", reference.scene, reference.scene_crc32),
                format!("{} (crc32 {:08x})", h.scene, h.scene_crc32),
            ));
        }
        if h.params != reference.params {
            return Err(differs(
                "parameters",
                reference.params.join(" "),
                h.params.join(" "),
            ));
        }
        if h.runs != reference.runs {
            return Err(differs(
                "number of runs",
                reference.runs.to_string(),
                h.runs.to_string(),
            ));
        }
        if t.columns != columns {
            return Err(differs(
                "columns",
                columns.iter().collect::<Vec<_>>().join(","),
                t.columns.iter().collect::<Vec<_>>().join(","),
            ));
        }
    }
    let mut slots: Vec<Option<(usize, csv::StringRecord)>> = vec![None; reference.runs];
    for (k, t) in tables.iter().enumerate() {
        for (index, record) in &t.rows {
            if *index >= reference.runs || !t.header.shard.contains(*index) {
                return Err(SweepError::ForeignRow {
                    file: t.file.clone(),
                    index: *index,
                    shard: t.header.shard,
                    runs: reference.runs,
                });
            }
            let slot = &mut slots[*index];
            if let Some((other, _)) = slot {
                return Err(SweepError::Duplicate {
                    index: *index,
                    file: t.file.clone(),
                    other: tables[*other].file.clone(),
                });
            }
            *slot = Some((k, record.clone()));
        }
    }
    let missing: Vec<usize> = (0..reference.runs)
        .filter(|&i| slots[i].is_none())
        .collect();
    if !missing.is_empty() {
        // With one N for all the tables, name the shards that are missing.
        let counts: BTreeSet<usize> = tables.iter().map(|t| t.header.shard.count).collect();
        let shards = match counts.iter().next() {
            Some(&n) if counts.len() == 1 => {
                let have: BTreeSet<usize> = tables.iter().map(|t| t.header.shard.index).collect();
                let lacking: Vec<String> = (0..n)
                    .filter(|i| !have.contains(i))
                    .map(|i| format!("{i}/{n}"))
                    .collect();
                if lacking.is_empty() {
                    String::new()
                } else {
                    format!(" (shards {} not given)", lacking.join(", "))
                }
            }
            _ => String::new(),
        };
        let shown: Vec<String> = missing.iter().take(10).map(usize::to_string).collect();
        return Err(SweepError::Missing {
            count: missing.len(),
            runs: reference.runs,
            first: format!(
                "{}{}{shards}",
                shown.join(", "),
                if missing.len() > 10 { ", …" } else { "" }
            ),
        });
    }
    let rows = slots.into_iter().flatten().map(|(_, r)| r).collect();
    let header = Header {
        shard: Shard::ALL,
        ..reference
    };
    Ok((header, columns.iter().map(str::to_owned).collect(), rows))
}
