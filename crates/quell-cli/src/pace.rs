//! The adaptive law's pace in the design report (`quell design`): what μ means under the regressor
//! scaling, and per channel the estimate of [`quell::diagnostics::estimate`].

use std::fmt::Write;

use quell::diagnostics::{estimate, RateEstimate, SteadyInput};
use quell::settings::fmt_4;
use quell::TimeUnit;
use quell::{Design, Scenario};
use serde_json::{json, Value};

/// The estimates for a scenario's design, on its true plant and signals over its horizon.
pub fn estimates(s: &Scenario, d: &Design) -> Vec<RateEstimate> {
    estimate(d, s.true_plant(), &s.reference, &s.disturbance, s.simulation.t_end)
}

/// `regressor_scaling`, `mu_meaning`, `adaptation` (one object per channel) and `steady_input`
/// added to the design's JSON.
/// The design's JSON report with its pace and steady input, as `quell design --json` writes it
/// (the automatic design's `design` too).
pub fn design_json(s: &Scenario, d: &Design) -> Value {
    let warnings = quell::design::warnings(d, &s.design);
    let mut json = with_pace(
        crate::report::with_warnings(crate::report::design_json(d), &warnings),
        d,
        &estimates(s, d),
        &s.steady_input(),
    );
    if let Value::Object(map) = &mut json {
        let rho = quell::sim::loop_rate(d, d.plant(), [&s.reference, &s.disturbance]);
        let deployment = json!({
            "loop_rate": rho,
            "sample_time_at_most": quell::sim::COARSE_SAMPLE / rho,
            "f32_pole_shift": quell::export::f32_pole_shift(d).shift,
        });
        map.insert("deployment".into(), deployment);
    }
    json
}

/// The design's text report with its pace, steady input and warnings, as `quell design` prints it
/// (the automatic design's report too: it had left out the pace, so a stiff or unexcited channel of
/// the design it chose was seen only by running `quell design` on the written file).
pub fn design_text(s: &Scenario, d: &Design) -> String {
    let pace = pace_text(d, &estimates(s, d), s.simulation.t_end, s.plant.time_unit);
    let effort =
        steady_text(&s.steady_input(), &s.names.inputs(s.plant.B.ncols()), s.plant.time_unit, s.truth.is_some());
    let warnings = crate::report::warnings_text(&quell::design::warnings(d, &s.design));
    let deployment = deployment_text(s, d);
    format!("{}{pace}{effort}{deployment}{warnings}", crate::report::design_text(d))
}

/// What the controller needs on hardware before any sampled run or export says it: the longest
/// sample time its loop tolerates, and how far f32 would move its poles.
fn deployment_text(s: &Scenario, d: &Design) -> String {
    let sim = &s.simulation;
    let (need, rho) = quell::sim::sample_time_need(
        d,
        [&s.reference, &s.disturbance],
        (sim.t_end, sim.output_step_given.then_some(sim.output_step)),
    );
    let unit = s.plant.time_unit;
    // The equilibrated κ₂ is the same in any units of the states: ∞ there is a defective matrix,
    // ∞ only as given is one whose states' scales lie beyond f64's resolution (a hydraulic
    // actuator's pressure in Pa beside positions in m, with distinct poles, had been called
    // defective and told to give distinct poles; helper tryout, 2026-12-07).
    let quell::export::PoleShift { shift, kappa, scale_free, what } = quell::export::f32_pole_shift(d);
    let precision = if !scale_free.is_finite() {
        format!("{what} has a defective eigenvector matrix (κ₂ = ∞): f32's rounding, as any model error, can move its poles without bound; export in f64 (the default) and give distinct poles")
    } else if !shift.is_finite() {
        format!(
            "{what}'s eigenvector matrix is too ill-conditioned in the states' coordinates as given for f64 to resolve (its poles are distinct: equilibrated κ₂ = {scale_free:.2e}), so the states' units lie far apart (e.g. Pa beside m) and f32's rounding may move its poles far: export in f64 (the default), or give the states units of similar sizes; quell run --sample-time T_s --precision f32 measures it, as quell export --precision f32 does before it writes"
        )
    } else if shift > quell::export::F32_POLE_SHIFT {
        format!(
            "f32 could move the poles of {what} by about {} (κ₂ = {kappa:.2e} × 6e-8, κ₂ in the states' coordinates as given; equilibrated, {scale_free:.2e}): export in f64 (the default), or choose poles that give a smaller κ₂; quell run --sample-time T_s --precision f32 measures it, as quell export --precision f32 does before it writes",
            quell::export::fmt_shift(shift)
        )
    } else {
        let measured = match s.simulation.precision {
            quell::controller::Precision::F32 => {
                "this scenario's sampled runs are in f32 and say how far it moves the loop"
            }
            quell::controller::Precision::F64 => {
                "quell run --sample-time T_s --precision f32 measures it, as quell export --precision f32 does before it writes"
            }
        };
        format!(
            "f32 moves the poles by at most {} (κ₂ = {kappa:.2e} × 6e-8): its poles allow f32, but the rounding its states accumulate over a run is not bounded by this: {measured}",
            quell::export::fmt_shift(shift)
        )
    };
    // The scenario's own sample time, which its runs verify, beside the bound's longest (a ball on
    // a plate verified at 1 ms had read "e.g. 0.005 s", at which it departed 200 %; helper tryout,
    // 2026-12-07).
    let own = sim.sample_time.map_or(String::new(), |t_s| {
        let (at, product) = (quell::settings::fmt_time(t_s), t_s * rho);
        if quell::sim::is_coarse(product) {
            format!("; this scenario samples at {at} {unit}, beyond it (T_s·ρ = {product:.2}): its sampled runs say how far the loop departs from the continuous one")
        } else {
            format!("; this scenario samples at {at} {unit} (T_s·ρ = {product:.2}), which its sampled runs judge: a longer T_s within the bound is not verified by them")
        }
    });
    format!(
        "
deployment (a sampled-data controller, docs/deployment.md):
  sample time: {need}; ρ = {} /{unit}, the loop's fastest rate (a bound the sampled loop needs, not one that suffices: a sampled run compares itself with its continuous loop and says where it departs){own}
  precision: {precision}
",
        fmt_4(rho)
    )
}

pub fn with_pace(mut design: Value, d: &Design, estimates: &[RateEstimate], steady: &SteadyInput) -> Value {
    if let Value::Object(map) = &mut design {
        map.insert("regressor_scaling".into(), json!(d.regressor_scaling().name()));
        map.insert("mu_meaning".into(), json!(d.regressor_scaling().mu_meaning(d.has_sizes())));
        map.insert("reference_sizes".into(), json!(d.reference_sizes()));
        map.insert("disturbance_sizes".into(), json!(d.disturbance_sizes()));
        map.insert("adaptation".into(), json!(estimates));
        map.insert("steady_input".into(), json!(steady));
    }
    design
}

/// The steady-state input as lines of text: per input its peak, range, mean and RMS and each frequency's
/// amplitude with the parts g alone and ω alone ask for, then the advice. `truth`: the simulated
/// plant is `[truth]`, not the design model.
pub fn steady_text(steady: &SteadyInput, inputs: &[String], time: TimeUnit, truth: bool) -> String {
    if steady.tones.is_empty() {
        return String::new();
    }
    let plant = if truth { "the simulated plant [truth]" } else { "the plant" };
    let mut s = format!(
        "\nsteady-state plant input u_f (y = g exactly: {plant} alone sets it, whatever the controller; per frequency in rad/{time}, the amplitude, and in brackets those g alone and ω alone ask for, which add as phasors):\n"
    );
    let four = |v: f64| match v {
        _ if v.is_finite() => fmt_4(v),
        _ if v < 0.0 => "−∞".to_string(),
        _ if v > 0.0 => "∞".to_string(),
        _ => "—".to_string(),
    };
    for (i, name) in inputs.iter().enumerate() {
        let parts: Vec<String> = steady
            .tones
            .iter()
            .map(|t| match t.transmission_zero {
                true => format!("{}: ∞ (a transmission zero)", fmt_4(t.frequency)),
                false => format!(
                    "{}: {} (g {}, ω {})",
                    fmt_4(t.frequency),
                    four(t.amplitude[i]),
                    four(t.for_reference[i]),
                    four(t.for_disturbance[i])
                ),
            })
            .collect();
        // The signed ends and mean, which a range that is not symmetric ([truth] u_min) is held to.
        let [low, high] = steady.range[i];
        let _ = writeln!(
            s,
            "  {name}: peak {} (from {} to {}, mean {}; RMS {}); {}",
            four(steady.peak[i]),
            four(low),
            four(high),
            four(steady.mean[i]),
            four(steady.rms[i]),
            parts.join(", ")
        );
    }
    for a in &steady.advice {
        let _ = writeln!(s, "    → {a}");
    }
    s
}

/// The components' sizes as the report's `regressor_scaling` line names them, where any is not 1.
fn sizes_text(d: &Design) -> String {
    if !d.has_sizes() {
        return String::new();
    }
    let list = |v: &[f64]| v.iter().map(|&x| fmt_4(x)).collect::<Vec<_>>().join(", ");
    let mut s = format!(", reference_sizes = [{}]", list(d.reference_sizes()));
    if !d.disturbance_sizes().is_empty() {
        s += &format!(", disturbance_sizes = [{}]", list(d.disturbance_sizes()));
    }
    s
}

/// The pace as lines of text.
pub fn pace_text(d: &Design, estimates: &[RateEstimate], t_end: f64, time: TimeUnit) -> String {
    let scaling = d.regressor_scaling();
    let mut s = format!(
        "\nadaptation (averaged over g and ω, before the run; t_end = {t_end} {time}):\n  regressor_scaling = \"{scaling}\"{}: {}\n",
        sizes_text(d),
        scaling.mu_meaning(d.has_sizes())
    );
    for e in estimates {
        let mut flag = match (e.stiff, e.weakly_excited) {
            (true, true) => "  ⚠ stiff, weakly excited",
            (true, false) => "  ⚠ stiff",
            (false, true) => "  ⚠ weakly excited",
            (false, false) => "",
        }
        .to_string();
        if e.adaptation_rate == 0.0 && e.lambda_max_omega > 0.0 {
            flag.push_str("  (μ = 0: the channel does not adapt, η̂ keeps its start)");
        }
        // From 3ρ (below the cost threshold of ⚠ stiff) the run is accurate only on the implicit
        // method, which `auto` then takes; say so, as the ratio is rounded.
        if !e.stiff && e.adaptation_rate >= quell::sim::EXPECT_STIFF_RATIO * e.loop_rate {
            flag.push_str(&format!(
                "  (≥ {}ρ: the automatic method takes η̂ implicitly from DOP853's stability bound)",
                quell::sim::EXPECT_STIFF_RATIO
            ));
        }
        let _ = writeln!(
            s,
            "  channel {}: μ λ_max(Ω̄) = {:.3e}/{time} ({:.2e}× ρ = {:.3e}/{time}), λ_max = {:.3e}, λ_min,excited = {:.3e} (excited rank {} of {}), convergence 1/(μ λ_min,excited) ≈ {}{flag}",
            e.channel,
            e.adaptation_rate,
            e.adaptation_rate / e.loop_rate,
            e.loop_rate,
            e.lambda_max_omega,
            e.lambda_min_excited_omega,
            e.excited_rank,
            d.q(),
            if e.convergence_time.is_finite() { format!("{:.3e} {time}", e.convergence_time) } else { "∞".into() },
        );
        for a in &e.advice {
            let _ = writeln!(s, "    → {a}");
        }
    }
    s
}
