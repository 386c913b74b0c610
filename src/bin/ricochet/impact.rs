//! `ricochet impact`: one impact problem per JSON line on standard input, one answer per
//! line on standard output (the contract of `DESIGN.md`).
//!
//! Standard input is bytes: it is split on `\n` and each line decoded by itself, so a line
//! that is not UTF-8, not JSON, too long or not a valid problem is an error line and the
//! next line is still answered. No answer holds a number that JSON cannot carry: an answer
//! with a non-finite number is an error line too (every such line counts as failed).

use std::io::{self, BufRead, BufReader, BufWriter, Write};
use std::process::ExitCode;

use anyhow::Context;
use ricochet::impact::{self, ContactVelocity, ImpactMatrix, ImpactProblem, Law, Outcome};

use crate::output::tell;
use serde::{Deserialize, Serialize};

/// Options of `ricochet impact`.
#[derive(clap::Args)]
#[command(after_help = "Input, one JSON object per line:\n  \
    {\"w\": [mnn, mnt, mtt], \"v_a\": [vn, vt], \"e\": 0.5, \"mu\": 0.2, \"law\": \"newton\"}\n\
    Output, one JSON object per input line (split on newlines), in order; \
    {\"error\": ..., \"line\": N} for a line that cannot be solved (not UTF-8, not JSON, \
    longer than 1 MiB, invalid data, no finite answer). The exit status is 1 if any line \
    failed.")]
pub struct Args {
    /// The law for lines that do not name one: newton, kane-levinson, poisson, stronge.
    #[arg(long, default_value = "newton")]
    law: Law,
}

/// One input line.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Request {
    /// `[m_nn, m_nt, m_tt]`.
    w: [f64; 3],
    /// `[v_n^A, v_t^A]`.
    v_a: [f64; 2],
    e: f64,
    mu: f64,
    law: Option<Law>,
}

/// One phase of the answer: its slip mode and the accumulated impulses at its end.
#[derive(Serialize)]
struct PhaseEnd {
    #[serde(rename = "type")]
    kind: &'static str,
    i_n: f64,
    i_t: f64,
}

/// One output line: the fields of `DESIGN.md`, then g, h, p, q and the phases.
#[derive(Serialize)]
struct Answer {
    law: Law,
    #[serde(rename = "type")]
    kind: &'static str,
    case: u8,
    alpha: f64,
    i_n: f64,
    i_t: f64,
    v_s: [f64; 2],
    delta_e: f64,
    work_n: f64,
    work_t: f64,
    g: f64,
    h: f64,
    p: f64,
    q: f64,
    phases: Vec<PhaseEnd>,
}

impl From<&Outcome> for Answer {
    fn from(out: &Outcome) -> Self {
        let c = &out.coefficients;
        Answer {
            law: out.law,
            kind: out.kind.name(),
            case: out.case.number(),
            alpha: c.alpha(),
            i_n: out.impulse.n,
            i_t: out.impulse.t,
            v_s: [out.v_s.n, out.v_s.t],
            delta_e: out.delta_e,
            work_n: out.work_n,
            work_t: out.work_t,
            g: c.g,
            h: c.h,
            p: c.p,
            q: c.q,
            phases: out
                .phases
                .iter()
                .map(|ph| PhaseEnd {
                    kind: ph.kind.name(),
                    i_n: ph.end.i.n,
                    i_t: ph.end.i.t,
                })
                .collect(),
        }
    }
}

impl Answer {
    /// The first number of the answer that JSON cannot carry (it would be `null`).
    fn first_non_finite(&self) -> Option<(&'static str, f64)> {
        let numbers = [
            ("alpha", self.alpha),
            ("i_n", self.i_n),
            ("i_t", self.i_t),
            ("v_s[0]", self.v_s[0]),
            ("v_s[1]", self.v_s[1]),
            ("delta_e", self.delta_e),
            ("work_n", self.work_n),
            ("work_t", self.work_t),
            ("g", self.g),
            ("h", self.h),
            ("p", self.p),
            ("q", self.q),
        ];
        let phases = (self.phases.iter())
            .flat_map(|ph| [("phases[].i_n", ph.i_n), ("phases[].i_t", ph.i_t)]);
        numbers
            .into_iter()
            .chain(phases)
            .find(|(_, x)| !x.is_finite())
    }
}

#[derive(Serialize)]
struct Failure {
    error: String,
    line: usize,
}

/// The longest line taken (bytes, without its newline); a longer one is an error line.
const MAX_LINE: usize = 1 << 20;

/// Solves one line (its bytes, without the newline); the error message is what goes into
/// `{"error": ...}`.
fn answer(bytes: &[u8], default_law: Law) -> Result<Answer, String> {
    let line = std::str::from_utf8(bytes).map_err(|e| {
        format!(
            "bad input: the line is not valid UTF-8 (byte {} of the line)",
            e.valid_up_to() + 1
        )
    })?;
    let line = line.strip_suffix('\r').unwrap_or(line);
    let req: Request = serde_json::from_str(line).map_err(|e| format!("bad input: {e}"))?;
    let problem = ImpactProblem::new(
        ImpactMatrix::new(req.w[0], req.w[1], req.w[2]),
        ContactVelocity::new(req.v_a[0], req.v_a[1]),
        req.e,
        req.mu,
    );
    let out = impact::solve(req.law.unwrap_or(default_law), &problem).map_err(|e| e.to_string())?;
    let answer = Answer::from(&out);
    match answer.first_non_finite() {
        None => Ok(answer),
        Some(("alpha", value)) => Err(format!(
            "α = v_t^A/|v_n^A| = {value} is beyond the range of doubles (|v_n^A| is too small \
             against v_t^A)"
        )),
        Some((what, value)) => Err(format!("the answer's {what} is not finite ({value})")),
    }
}

/// Reads the next line of `input` into `line` (without its `\n`), keeping at most
/// [`MAX_LINE`] bytes of it; returns its whole length, `None` at the end of the input.
fn read_line(input: &mut impl BufRead, line: &mut Vec<u8>) -> io::Result<Option<usize>> {
    line.clear();
    let mut length = None;
    loop {
        let available = match input.fill_buf() {
            Ok(bytes) => bytes,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        if available.is_empty() {
            return Ok(length);
        }
        let newline = available.iter().position(|&b| b == b'\n');
        let chunk = &available[..newline.unwrap_or(available.len())];
        let room = MAX_LINE.saturating_sub(line.len());
        line.extend_from_slice(&chunk[..chunk.len().min(room)]);
        *length.get_or_insert(0) += chunk.len();
        let used = chunk.len() + usize::from(newline.is_some());
        input.consume(used);
        if newline.is_some() {
            return Ok(length);
        }
    }
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let mut input = BufReader::new(io::stdin().lock());
    let mut output = BufWriter::new(io::stdout().lock());
    let mut failed = 0usize;
    let mut line = Vec::new();
    for number in 1.. {
        let Some(length) = read_line(&mut input, &mut line).context("reading standard input")?
        else {
            break;
        };
        let answer = if length > MAX_LINE {
            Err(format!(
                "bad input: the line is {length} bytes long, more than the {MAX_LINE} a \
                 problem may take"
            ))
        } else {
            answer(&line, args.law)
        };
        if answer.is_err() {
            failed += 1;
        }
        let written = match answer {
            Ok(ans) => serde_json::to_writer(&mut output, &ans),
            Err(error) => serde_json::to_writer(
                &mut output,
                &Failure {
                    error,
                    line: number,
                },
            ),
        }
        .map_err(io::Error::from)
        .and_then(|()| output.write_all(b"\n"))
        // Answer at once when the caller waits for us (an interactive or co-process use);
        // batch the writes while more input is already buffered.
        .and_then(|()| match input.buffer().is_empty() {
            true => output.flush(),
            false => Ok(()),
        });
        match written {
            // The reader is gone (`| head`): no one takes the other answers.
            Err(e) if crate::output::is_broken_pipe(&e) => return Ok(status(failed)),
            written => written.context("writing standard output")?,
        }
    }
    match output.flush() {
        Err(e) if crate::output::is_broken_pipe(&e) => {}
        flushed => flushed.context("writing standard output")?,
    }
    Ok(status(failed))
}

/// The exit status after `failed` failed lines (said on standard error).
fn status(failed: usize) -> ExitCode {
    if failed > 0 {
        tell!("ricochet impact: {failed} line(s) failed");
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}
