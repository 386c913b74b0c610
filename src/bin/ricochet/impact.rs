//! `ricochet impact`: one impact problem per JSON line on standard input, one answer per
//! line on standard output (the contract of `DESIGN.md`).

use std::io::{self, BufRead, BufReader, BufWriter, Write};
use std::process::ExitCode;

use anyhow::Context;
use ricochet::impact::{self, ContactVelocity, ImpactMatrix, ImpactProblem, Law, Outcome};
use serde::{Deserialize, Serialize};

/// Options of `ricochet impact`.
#[derive(clap::Args)]
#[command(after_help = "Input, one JSON object per line:\n  \
    {\"w\": [mnn, mnt, mtt], \"v_a\": [vn, vt], \"e\": 0.5, \"mu\": 0.2, \"law\": \"newton\"}\n\
    Output, one JSON object per input line, in order; {\"error\": ...} for a line that \
    cannot be solved. The exit status is 1 if any line failed.")]
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

#[derive(Serialize)]
struct Failure {
    error: String,
    line: usize,
}

/// Solves one line; the error message is what goes into `{"error": ...}`.
fn answer(line: &str, default_law: Law) -> Result<Answer, String> {
    let req: Request = serde_json::from_str(line).map_err(|e| format!("bad input: {e}"))?;
    let problem = ImpactProblem::new(
        ImpactMatrix::new(req.w[0], req.w[1], req.w[2]),
        ContactVelocity::new(req.v_a[0], req.v_a[1]),
        req.e,
        req.mu,
    );
    let out = impact::solve(req.law.unwrap_or(default_law), &problem).map_err(|e| e.to_string())?;
    Ok(Answer::from(&out))
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let mut input = BufReader::new(io::stdin().lock());
    let mut output = BufWriter::new(io::stdout().lock());
    let mut failed = 0usize;
    let mut line = String::new();
    for number in 1.. {
        line.clear();
        if input
            .read_line(&mut line)
            .context("reading standard input")?
            == 0
        {
            break;
        }
        match answer(line.trim_end_matches(['\n', '\r']), args.law) {
            Ok(ans) => serde_json::to_writer(&mut output, &ans)?,
            Err(error) => {
                failed += 1;
                serde_json::to_writer(
                    &mut output,
                    &Failure {
                        error,
                        line: number,
                    },
                )?;
            }
        }
        output.write_all(b"\n")?;
        // Answer at once when the caller waits for us (an interactive or co-process use);
        // batch the writes while more input is already buffered.
        if input.buffer().is_empty() {
            output.flush().context("writing standard output")?;
        }
    }
    output.flush().context("writing standard output")?;
    if failed > 0 {
        eprintln!("ricochet impact: {failed} line(s) failed");
        Ok(ExitCode::FAILURE)
    } else {
        Ok(ExitCode::SUCCESS)
    }
}
