//! `quell tune`: per-channel searches over μ_i (the study's `[tune]`), the chosen μ, each channel's
//! curve (tune.csv, tune.json, tune.png/.svg) and the check that the joint run reproduces them.

use std::path::PathBuf;

use quell::study::{self, Study, TuneResult};

use crate::output::{prepare_out, write_atomic};
use crate::Failure;

#[derive(clap::Args)]
pub struct TuneArgs {
    /// Study file (TOML) with a [tune] table: objective, mu = [μ_min, μ_max] per channel, max_u.
    study: PathBuf,
    /// Output directory.
    #[arg(long, default_value = "quell-tune")]
    out: PathBuf,
    /// Worker threads (default: one per core).
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = crate::sweep::parse_jobs)]
    jobs: Option<usize>,
    /// Skip tune.png/.svg.
    #[arg(long)]
    no_plots: bool,
}

pub fn tune(args: &TuneArgs) -> Result<(), Failure> {
    let path = &args.study;
    let study = Study::from_path(path).map_err(|e| Failure::Input(format!("{}: {e}", path.display())))?;
    if study.tune.is_none() {
        return Err(Failure::Input(format!(
            "{}: tune: missing; `quell tune` needs a [tune] table, e.g. [tune] objective = \"settle_t\", mu = [1.0, 200.0], max_u = 50.0",
            path.display()
        )));
    }
    let pool = crate::sweep::thread_pool(args.jobs, usize::MAX)?;
    // The searches write nothing until every channel is done, so a signal quits at once.
    crate::interrupt::Interrupt::quit_with("interrupted during tuning; nothing was written (tune.csv and tune.json are written once every channel's search is done)");
    prepare_out(&args.out, &["tune.json", "tune.csv"])?;
    let result =
        pool.install(|| study::tune(&study)).map_err(|e| Failure::Input(format!("{}: {e}", path.display())))?;
    let failed = |e: std::io::Error| Failure::Run(format!("writing {}: {e}", args.out.display()));
    crate::output::write_json(&args.out.join("tune.json"), &result).map_err(failed)?;
    write_atomic(&args.out.join("tune.csv"), |w| write_curves(w, &result)).map_err(failed)?;
    if !args.no_plots {
        crate::plot::plot_tune(&args.out, &result).map_err(failed)?;
    }
    crate::print_stdout(&report(&result));
    if let Some(c) = result.channels.iter().find(|c| c.chosen.is_none()) {
        return Err(Failure::Input(format!(
            "channel {}: no μ in tune.mu[{}] completed with max |u_{}| ≤ tune.max_u[{}], max |u_f,{}| ≤ tune.max_uf[{}] and a finite {}; widen the bounds, raise the limits or lengthen simulation.t_end (the curve is in {})",
            c.channel + 1,
            c.channel,
            c.channel + 1,
            c.channel,
            c.channel + 1,
            c.channel,
            result.objective.name(),
            args.out.join("tune.csv").display()
        )));
    }
    Ok(())
}

/// tune.csv: every evaluation of every channel's search.
fn write_curves(w: &mut dyn std::io::Write, r: &TuneResult) -> std::io::Result<()> {
    writeln!(w, "channel,mu,objective,outcome,tail_max_e,tail_rms_e,max_u,max_uf,settle_t,chosen")?;
    let opt = |v: Option<f64>| v.map_or(String::new(), |v| v.to_string());
    for c in &r.channels {
        for p in &c.curve {
            let f = p.figures;
            let chosen = c.chosen.as_ref().is_some_and(|q| q.mu == p.mu);
            writeln!(
                w,
                "{},{},{},{},{},{},{},{},{},{chosen}",
                c.channel + 1,
                p.mu,
                opt(p.objective),
                p.outcome.as_str(),
                opt(f.map(|f| f.tail_max_e)),
                opt(f.map(|f| f.tail_rms_e)),
                opt(f.map(|f| f.max_u)),
                opt(f.map(|f| f.max_uf)),
                opt(f.and_then(|f| f.settle_t)),
            )?;
        }
    }
    Ok(())
}

/// The chosen μ and the joint check, one line per channel.
fn report(r: &TuneResult) -> String {
    let mut s = format!("objective: {}\n", r.objective.name());
    for (c, (d, ok)) in r.channels.iter().zip(r.joint_difference.iter().zip(&r.reproduced)) {
        match &c.chosen {
            Some(p) => s.push_str(&format!(
                "channel {}: mu = {:.6} ({} evaluations), objective {:.6e}; joint run {} (difference {})\n",
                c.channel + 1,
                p.mu,
                c.curve.len(),
                p.objective.unwrap_or(f64::NAN),
                if *ok { "reproduces it" } else { "does NOT reproduce it" },
                d.map_or("n/a".to_string(), |d| format!("{d:.3e}")),
            )),
            None => s.push_str(&format!("channel {}: no feasible mu in the bounds\n", c.channel + 1)),
        }
    }
    s.push_str(&format!("tuned mu = [{}]\n", r.mu.iter().map(|m| format!("{m:.6}")).collect::<Vec<_>>().join(", ")));
    s
}
