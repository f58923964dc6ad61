//! `quell tune`: per-channel searches over μ_i (the study's `[tune]`), the chosen μ, each channel's
//! curve (tune.csv, tune.json, tune.png/.svg) and the check that the joint run reproduces them.

use std::path::PathBuf;

use quell::study::{self, TuneOptions, TunePoint, TuneResult};

use crate::interrupt::Interrupt;
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
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = crate::sweep::parse_jobs)]
    jobs: Option<usize>,
    /// Skip tune.png/.svg.
    #[arg(long)]
    no_plots: bool,
}

pub fn tune(args: &TuneArgs) -> Result<(), Failure> {
    let path = &args.study;
    let study = crate::sweep::read_study(path)?;
    if study.tune.is_none() {
        return Err(Failure::Input(format!(
            "{}: tune: missing; `quell tune` needs a [tune] table, e.g. [tune] objective = \"settle_t\", mu = [1.0, 200.0], max_u = 50.0",
            path.display()
        )));
    }
    let pool = crate::sweep::thread_pool(args.jobs, usize::MAX)?;
    let files = ["tune.json", "tune.csv", "tune.png", "tune.svg"];
    crate::output::not_the_study_inputs(path, study.scenario_path.as_deref(), &args.out, &files)?;
    prepare_out(&args.out, &files)?;
    for w in study::tune_cautions(&study) {
        eprintln!("⚠ warning: {w}");
    }
    // Ctrl-C or SIGTERM: the first stops the searches (runs under way are abandoned) and the
    // points evaluated so far are written, marked partial; a second before writing begins quits.
    let interrupt = Interrupt::install("interrupted twice; stopped without writing files");
    let spec = study.tune.as_ref().expect("checked above");
    let (bar, round) = round_bar(spec);
    let on_point = |_: usize, _: &TunePoint| count(&bar, round);
    let options = TuneOptions { stop: Some(interrupt.stop_flag()), on_point: Some(&on_point) };
    let result = pool.install(|| study::tune(&study, &options));
    bar.finish_and_clear();
    let result = result.map_err(|e| Failure::Input(format!("{}: {e}", path.display())))?;
    // Stopped in a later round of searches (a joint run had broken a limit): the round before is
    // complete, and written as the result.
    if !result.partial && interrupt.stop_flag().load(std::sync::atomic::Ordering::Relaxed) {
        eprintln!("⚠ warning: interrupted after a complete round of searches, which is written (a later round within tightened limits, if one was under way, was abandoned)");
    }
    interrupt.start_writing();
    let failed = |e: std::io::Error| Failure::Run(format!("writing {}: {e}", args.out.display()));
    crate::output::write_json(&args.out.join("tune.json"), &result).map_err(failed)?;
    write_atomic(&args.out.join("tune.csv"), |w| write_curves(w, &result)).map_err(failed)?;
    // A figure of an earlier tuning must not stand beside the new curves.
    crate::output::remove_figures(&args.out, |stem| stem == "tune", &[]).map_err(failed)?;
    if !args.no_plots {
        crate::plot::plot_tune(&args.out, &result, study.time_unit(), &study.outputs()).map_err(failed)?;
    }
    crate::print_stdout(&report(&result, spec, study.time_unit()));
    if result.partial {
        let evaluations: usize = result.channels.iter().map(|c| c.curve.len()).sum();
        let best =
            if evaluations == 0 { "the μ printed is the scenario's" } else { "the μ printed is the best of them" };
        return Err(Failure::Run(format!(
            "interrupted after {evaluations} evaluations, before the joint run; they are in {} (marked partial), and {best}",
            args.out.join("tune.csv").display()
        )));
    }
    // Every channel without a feasible μ, not the first alone (each would cost another round).
    let none: Vec<String> = result
        .channels
        .iter()
        .filter(|c| c.chosen.is_none())
        .map(|c| {
            format!(
                "channel {}: {}",
                c.channel + 1,
                c.why_none(spec, "tune.", (study.u_max(c.channel), study.steady_input_peak(c.channel)))
            )
        })
        .collect();
    if !none.is_empty() {
        return Err(Failure::Input(format!(
            "{} (the curves are in {})",
            none.join("\n"),
            args.out.join("tune.csv").display()
        )));
    }
    // After the channels without a feasible μ: the joint run then holds the scenario's μ there.
    match result.joint_limits_caution(spec, "tune.") {
        Some(broken) => Err(Failure::Input(broken)),
        None => Ok(()),
    }
}

/// tune.csv: every evaluation of every channel's search.
fn write_curves(w: &mut dyn std::io::Write, r: &TuneResult) -> std::io::Result<()> {
    writeln!(w, "channel,mu,objective,outcome,reason,tail_max_e,tail_rms_e,max_u,max_uf,settle_t,chosen")?;
    let num = quell::study::csv_number;
    let opt = |v: Option<f64>| v.map_or(String::new(), num);
    for c in &r.channels {
        for p in &c.curve {
            let f = p.figures;
            let chosen = c.chosen.as_ref().is_some_and(|q| q.mu == p.mu);
            writeln!(
                w,
                "{},{},{},{},{},{},{},{},{},{},{chosen}",
                c.channel + 1,
                num(p.mu),
                opt(p.objective),
                p.outcome.as_str(),
                quell::study::csv_field(&p.reason),
                opt(f.map(|f| f.tail_max_e)),
                opt(f.map(|f| f.tail_rms_e)),
                opt(f.map(|f| f.max_u)),
                opt(f.map(|f| f.max_uf)),
                opt(f.and_then(|f| f.settle_t)),
            )?;
        }
    }
    if r.partial {
        let n: usize = r.channels.iter().map(|c| c.curve.len()).sum();
        writeln!(w, "# partial: {n} evaluations were carried out before the tuning was interrupted (no joint run)")?;
    }
    Ok(())
}

/// The chosen μ and the joint check, one line per channel; a settling time in `unit`.
/// The tuning's progress bar, one round of evaluations long, and that round's count.
fn round_bar(spec: &quell::study::TuneSpec) -> (indicatif::ProgressBar, u64) {
    let round = (spec.bounds.len() * (spec.points + if spec.refine == 0 { 0 } else { spec.refine.max(2) })) as u64;
    (crate::progress_bar(round, "tuning {bar:40} {pos}/{len} evaluations, {elapsed_precise} elapsed"), round)
}

/// One evaluation on `bar`; a later round of searches (a joint run beyond a limit) adds `round` to
/// its length when the count reaches the end.
fn count(bar: &indicatif::ProgressBar, round: u64) {
    if bar.position() >= bar.length().unwrap_or(0) {
        bar.inc_length(round);
    }
    bar.inc(1)
}

fn report(r: &TuneResult, spec: &quell::study::TuneSpec, unit: quell::TimeUnit) -> String {
    let mut s = match r.objective {
        quell::study::Objective::SettleT => format!("objective: settle_t, in {}\n", unit.name()),
        other => format!("objective: {}\n", other.name()),
    };
    for (c, (d, ok)) in r.channels.iter().zip(r.joint_difference.iter().zip(&r.reproduced)) {
        match &c.chosen {
            Some(p) => s.push_str(&format!(
                "channel {}: mu = {} ({}), objective {:.6e}{}; joint run {} (difference {}){}{}\n",
                c.channel + 1,
                mu_6(p.mu),
                if c.curve.len() == 1 { "1 evaluation".to_string() } else { format!("{} evaluations", c.curve.len()) },
                p.objective.unwrap_or(f64::NAN),
                // A smaller μ whose objective is not the least: what it ties with.
                c.tie.filter(|t| p.objective.is_some_and(|v| v > t.least)).map_or(String::new(), |t| format!(
                    ", a tie with the least, {:.6e} at mu = {} (ties up to {:.6e}; docs/studies.md)",
                    t.least,
                    mu_6(t.mu),
                    t.bound
                )),
                match (r.partial, *ok, quell::study::joint_better(*d)) {
                    (true, ..) => "not carried out (interrupted)",
                    (false, true, _) => "reproduces it",
                    (false, false, true) => "does better than its search (the channels interact)",
                    (false, false, false) => "does NOT reproduce it",
                },
                d.map_or("n/a".to_string(), |d| format!("{d:.3e}")),
                if r.partial || r.within_limits.get(c.channel).copied().flatten().unwrap_or(true) {
                    String::new()
                } else {
                    format!(", but BREAKS {} there", r.joint_broken(spec, c.channel, "tune.").join(", "))
                },
                // Interrupted, the largest μ evaluated is not the range's end.
                c.bound_note(&format!("tune.mu[{}]", c.channel))
                    .filter(|_| !r.partial)
                    .map_or(String::new(), |note| format!("; {note}")),
            )),
            None if r.partial && c.curve.is_empty() => {
                s.push_str(&format!("channel {}: not evaluated (tuning interrupted)\n", c.channel + 1))
            }
            None if r.partial => s.push_str(&format!(
                "channel {}: no feasible mu among the {} evaluated before the interruption\n",
                c.channel + 1,
                c.curve.len()
            )),
            None => s.push_str(&format!(
                "channel {}: no feasible mu among the {} evaluated in the bounds\n",
                c.channel + 1,
                c.curve.len()
            )),
        }
    }
    // A channel without a feasible μ keeps the scenario's (TuneResult::mu): not a tuned value.
    let untuned: Vec<String> =
        r.channels.iter().filter(|c| c.chosen.is_none()).map(|c| (c.channel + 1).to_string()).collect();
    let plural = if untuned.len() > 1 { "s" } else { "" };
    let note = |why: &str| match untuned.is_empty() {
        true => String::new(),
        false => format!(" (channel{plural} {}: the scenario's mu, {why})", untuned.join(", ")),
    };
    let (label, note) = match (r.partial, untuned.is_empty()) {
        (true, _) => ("best mu so far (tuning interrupted)", note("not yet tuned")),
        (false, true) => ("tuned mu", String::new()),
        (false, false) => ("mu", note("unchanged; no feasible mu")),
    };
    let mu = r.mu.iter().map(|&m| mu_6(m)).collect::<Vec<_>>().join(", ");
    s.push_str(&format!("{label} = [{mu}]{note}\n"));
    if let Some(note) = r.searched_note("tune.") {
        s.push_str(&format!("note: {note}\n"));
    }
    s
}

/// μ to six decimals, or six significant digits where that would hide it (1e-15 read 0.000000).
fn mu_6(mu: f64) -> String {
    if mu == 0.0 || (1e-3..1e6).contains(&mu.abs()) {
        format!("{mu:.6}")
    } else {
        format!("{mu:.5e}")
    }
}

#[cfg(test)]
mod tests {
    use super::{mu_6, report};
    use quell::study::{Objective, Outcome, TuneCurve, TunePoint, TuneResult};

    #[test]
    fn a_small_mu_is_printed_in_significant_digits() {
        assert_eq!(
            [mu_6(3.16227766016838), mu_6(1e-15), mu_6(2.5e7), mu_6(0.0)],
            ["3.162278", "1.00000e-15", "2.50000e7", "0.000000"]
        );
    }

    #[test]
    fn an_interrupted_report_says_what_was_not_evaluated() {
        // Stopped during channel 1's search: its best so far is its largest μ evaluated, not the
        // upper end of tune.mu[0], and channel 2 was never evaluated (it read "no feasible mu in
        // the bounds").
        let point = |mu: f64, objective: f64| TunePoint {
            mu,
            objective: Some(objective),
            outcome: Outcome::Completed,
            reason: String::new(),
            figures: None,
        };
        let curve = vec![point(1000.0, 3.0), point(37275.9, 1.0)];
        let result = TuneResult {
            objective: Objective::TailRmsE,
            channels: vec![
                TuneCurve { channel: 0, chosen: Some(curve[1].clone()), curve, tie: None },
                TuneCurve { channel: 1, curve: vec![], chosen: None, tie: None },
            ],
            mu: vec![37275.9, 1.0],
            joint: None,
            joint_difference: vec![None, None],
            reproduced: vec![false, false],
            within_limits: vec![None, None],
            partial: true,
            searched_within: None,
        };
        let spec = quell::study::TuneSpec {
            objective: Objective::TailRmsE,
            bounds: vec![[1.0, 1e5]; 2],
            max_u: vec![f64::INFINITY; 2],
            max_uf: vec![f64::INFINITY; 2],
            points: 2,
            refine: 0,
        };
        let text = report(&result, &spec, quell::TimeUnit::default());
        assert!(text.contains("channel 2: not evaluated (tuning interrupted)"), "{text}");
        // Channel 2's μ is the scenario's, not a result of the search.
        assert!(
            text.contains("best mu so far (tuning interrupted) = [37275.900000, 1.000000] (channel 2: the scenario's mu, not yet tuned)"),
            "{text}"
        );
        assert!(!text.contains("end of tune.mu"), "{text}");
        assert!(!text.contains("no feasible"), "{text}");
    }

    /// A later round of searches lengthens the bar by a round where the count reaches its end,
    /// so that it never reads more evaluations done than it holds.
    #[test]
    fn the_progress_bar_grows_by_a_round_for_a_later_round() {
        let bar = indicatif::ProgressBar::hidden();
        bar.set_length(4);
        for _ in 0..5 {
            super::count(&bar, 4);
        }
        assert_eq!((bar.position(), bar.length()), (5, Some(8)));
    }
}
