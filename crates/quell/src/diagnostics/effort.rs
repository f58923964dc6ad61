//! The plant input that exact tracking and rejection cost (the design report): in steady state
//! y = C x + Q ω equals g, and at each frequency w of g and ω the plant (1) then fixes the input
//! u_f = −K x̂ + F u_d (5) whatever the controller:
//!
//! ```text
//! [ jwI − A   −B ] [X]   [ D W     ]
//! [    C       0 ] [U] = [ G − Q W ]
//! ```
//!
//! (G, W the phasors of g and ω at w; the delays τ_i act on u_d inside the controller, not on u_f).
//! Every design that converges ends with this u_f, so it is a floor on the actuator effort, and it
//! tells which harmonic of ω costs the effort: one that moves y by less than the tail bound yet
//! takes a large share of the input is better traded for effort (`u_limit` of the automatic design).

use nalgebra::{Complex, DMatrix, DVector};
use serde::Serialize;

use crate::averaged::{complex, resolvent};
use crate::linalg::eigenvalues;
use crate::plant::Plant;
use crate::settings::{fmt_4, fmt_short, Actuator, TimeUnit};
use crate::signal::{Component, Harmonic, Signal};

use super::TAIL_BOUND;

type C64 = Complex<f64>;

/// A harmonic of ω whose cancellation costs at least this share of an input's steady-state peak
/// while it moves no output by more than the tail bound gets advice.
pub const COSTLY_SHARE: f64 = 0.25;

/// The system matrix [jwI − A, −B; C, 0], rows and columns scaled to unit largest entry, counts as
/// singular (w a transmission zero of (A, B, C)) below this σ_min/σ_max.
const ZERO_RCOND: f64 = 1e-11;

/// One frequency's share of the steady-state input.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InputTone {
    /// rad per unit of time (0: the biases).
    pub frequency: f64,
    /// w is a transmission zero of (A, B, C): y = g cannot be held at it, whatever the input (the
    /// amplitudes are then ∞, null in JSON).
    pub transmission_zero: bool,
    /// Per input: the amplitude of u_f,i at this frequency (|value| for the biases).
    pub amplitude: Vec<f64>,
    /// Per input: the amplitude g alone asks for, and ω alone (phasors: the two need not add up
    /// to `amplitude`).
    pub for_reference: Vec<f64>,
    pub for_disturbance: Vec<f64>,
    /// Per output: the amplitude of ω's forced response at y with the input held at 0,
    /// C (jwI − A)⁻¹ D W + Q W (for an unstable plant, the particular solution); `None` where jw
    /// is an eigenvalue of A (unbounded).
    pub disturbance_output: Option<Vec<f64>>,
}

impl InputTone {
    /// A harmonic of ω that the loop may let pass: ω has one at this frequency and its forced
    /// response (input held at 0) stays within `bounds` (the tail bounds, per output) at every
    /// output.
    fn passable(&self, bounds: &[f64]) -> bool {
        self.frequency > 0.0 && !self.transmission_zero && self.forced_within(bounds)
    }

    /// ω has a part at this frequency (its bias too) whose forced response (input held at 0)
    /// stays within `bounds` at every output.
    pub fn forced_within(&self, bounds: &[f64]) -> bool {
        self.for_disturbance.iter().any(|&u| u > 0.0)
            && self.disturbance_output.as_ref().is_some_and(|y| y.iter().zip(bounds).all(|(y, b)| y <= b))
    }

    /// Input i's amplitude here with a passable harmonic let pass: g's part alone.
    fn kept(&self, i: usize, bounds: &[f64]) -> f64 {
        if self.passable(bounds) {
            self.for_reference[i]
        } else {
            self.amplitude[i]
        }
    }
}

impl SteadyInput {
    /// Per input, the steady-state peak with the passable harmonics of ω let pass (ω has one there
    /// and its forced response stays within `bounds`; their input only g's part): the sum of the
    /// amplitudes (an upper bound where the frequencies are whole multiples of one),
    /// [`SteadyInput::peak`] where none is passable. A ball on a plate whose 18.85 rad/s vibration
    /// moved the ball 1.4e-4 m within a 5e-4 m bound was told that its plant "needs" 0.54 V against
    /// a 0.3 V limit, 0.47 V of it for that vibration (helper tryout, 2026-12-07).
    pub fn peak_letting_pass(&self, bounds: &[f64]) -> Vec<f64> {
        if !self.tones.iter().any(|t| t.passable(bounds)) {
            return self.peak.clone();
        }
        // The sum bounds the peak from above: never above the peak with nothing let pass.
        (0..self.peak.len())
            .map(|i| self.tones.iter().map(|t| t.kept(i, bounds)).sum::<f64>().min(self.peak[i]))
            .collect()
    }
}

/// The steady-state plant input u_f of exact tracking and rejection ([module docs](self)).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SteadyInput {
    /// Ascending in frequency; empty when g and ω are zero.
    pub tones: Vec<InputTone>,
    /// Per input: max |u_f,i| in steady state, the sum of the amplitudes (approached when the
    /// frequencies are incommensurate) or, where they are whole multiples of one, the maximum
    /// over that period ([`Component::peak`]); ∞ at a transmission zero.
    pub peak: Vec<f64>,
    /// Per input: [min, max] of u_f,i in steady state, found as `peak` is ([`Component::range`]);
    /// [−∞, ∞] at a transmission zero.
    pub range: Vec<[f64; 2]>,
    /// Per input: the mean of u_f,i in steady state (its bias); NaN at a transmission zero.
    pub mean: Vec<f64>,
    /// Per input: the RMS of u_f,i in steady state, √(b² + Σ a²/2): a lower bound of the peak.
    pub rms: Vec<f64>,
    /// One line per transmission zero among the frequencies, per costly harmonic of ω
    /// ([`COSTLY_SHARE`]) and per input whose actuator limit the steady state exceeds.
    pub advice: Vec<String>,
}

/// The steady-state input of `plant` under g = `reference`, ω = `disturbance`, against the
/// `actuator`'s limits (`truth.u_max`, `u_min`) where given. `names` labels the inputs and outputs
/// in the advice.
pub fn steady_input(
    plant: &Plant,
    (reference, disturbance): (&Signal, &Signal),
    actuator: Option<&Actuator>,
    names: (&[String], &[String]),
) -> SteadyInput {
    let m = plant.B.ncols();
    // Without A's eigenvalues (their iteration failed), no forced response either.
    let eigs = eigenvalues(&plant.A).ok();
    let mut signals: Vec<Component> = vec![Component::default(); m];
    let mut tones = Vec::new();
    for t in crate::averaged::tones(reference, disturbance) {
        let S = system_matrix(plant, t.w);
        let zero = transmission_zero(&S);
        let [for_reference, for_disturbance] = input_phasors(plant, S, &t.g, &t.omega);
        let both = &for_reference + &for_disturbance;
        for (u, c) in both.iter().zip(&mut signals) {
            // a sin(wt + φ) has the phasor a e^{j(φ − π/2)} (crate::averaged's convention).
            let phase = u.arg() + std::f64::consts::FRAC_PI_2;
            match t.w {
                0.0 => c.bias += u.re,
                w => c.harmonics.push(Harmonic { amplitude: u.norm(), frequency: w, phase }),
            }
        }
        // Round-off of an exact cancellation (1e-16 of the other part) reads as 0.
        let size = both.iter().chain(&for_reference).chain(&for_disturbance).map(|u| u.norm()).fold(0.0, f64::max);
        let amplitude = |v: &DVector<C64>| -> Vec<f64> {
            v.iter()
                .map(|u| {
                    if zero {
                        f64::INFINITY
                    } else if u.norm() <= 1e-12 * size {
                        0.0
                    } else {
                        u.norm()
                    }
                })
                .collect()
        };
        tones.push(InputTone {
            frequency: t.w,
            transmission_zero: zero,
            amplitude: amplitude(&both),
            for_reference: amplitude(&for_reference),
            for_disturbance: amplitude(&for_disturbance),
            disturbance_output: eigs.as_deref().and_then(|e| forced_output(plant, e, t.w, &t.omega)),
        });
    }
    let any_zero = tones.iter().any(|t| t.transmission_zero);
    let peak = signals.iter().map(|c| if any_zero { f64::INFINITY } else { c.peak() }).collect();
    let range = (signals.iter())
        .map(|c| if any_zero { [f64::NEG_INFINITY, f64::INFINITY] } else { c.range().into() })
        .collect();
    let rms = (0..m)
        .map(|i| {
            let power = |t: &InputTone| t.amplitude[i].powi(2) * if t.frequency == 0.0 { 1.0 } else { 0.5 };
            tones.iter().map(power).fold(0.0, |a, p| a + p).sqrt()
        })
        .collect();
    let mean = signals.iter().map(|c| if any_zero { f64::NAN } else { c.mean() }).collect();
    let mut steady = SteadyInput { tones, peak, range, mean, rms, advice: vec![] };
    let unit = plant.time_unit;
    let mut advice: Vec<String> =
        steady.tones.iter().filter(|t| t.transmission_zero).map(|t| zero_advice(t.frequency, unit)).collect();
    advice.extend(costly_harmonics(&steady, reference, names, unit));
    advice.extend(actuator.into_iter().flat_map(|a| beyond_limits(&steady, a, names.0)));
    steady.advice = advice;
    steady
}

/// Whether w is a transmission zero of (A, B, C): the system matrix of [module docs](self),
/// equilibrated, is singular to [`ZERO_RCOND`]. (Its LU solve would return a finite 1e16.)
fn transmission_zero(S: &DMatrix<C64>) -> bool {
    let mut S = S.clone();
    for mut row in S.row_iter_mut() {
        let top = row.iter().map(|z| z.norm()).fold(0.0, f64::max);
        if top > 0.0 {
            row /= C64::new(top, 0.0);
        }
    }
    for mut col in S.column_iter_mut() {
        let top = col.iter().map(|z| z.norm()).fold(0.0, f64::max);
        if top > 0.0 {
            col /= C64::new(top, 0.0);
        }
    }
    let sv = S.svd(false, false).singular_values;
    let (lo, hi) = sv.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    lo.is_nan() || lo <= ZERO_RCOND * hi
}

/// A frequency of g or ω at a transmission zero: what it means and what to change.
fn zero_advice(w: f64, unit: TimeUnit) -> String {
    format!(
        "{} rad/{unit} is a transmission zero of (A, B, C): no input holds y = g there, so tracking g or rejecting ω at that frequency is impossible whatever the design or the actuator (the adaptive command grows without converging); take that frequency out of the reference, or measure other outputs",
        fmt_4(w)
    )
}

/// [jwI − A, −B; C, 0] ([module docs](self)).
fn system_matrix(plant: &Plant, w: f64) -> DMatrix<C64> {
    let (n, m) = (plant.A.nrows(), plant.B.ncols());
    let mut S = DMatrix::<C64>::zeros(n + m, n + m);
    S.view_mut((0, 0), (n, n)).copy_from(&-complex(&plant.A));
    for i in 0..n {
        S[(i, i)] += C64::new(0.0, w);
    }
    S.view_mut((0, n), (n, m)).copy_from(&-complex(&plant.B));
    S.view_mut((n, 0), (m, n)).copy_from(&complex(&plant.C));
    S
}

/// U for g alone and for ω alone at one frequency, their phasors G and W, `S` the system matrix
/// there: one LU, two right-hand sides [0; G] and [D W; −Q W]. A zero signal asks for nothing; an
/// exactly singular S gives ∞; an entry within rounding of |S⁻¹| |rhs| is 0 (a missile's gust
/// bias, which does not reach y, had asked 3.8e-19 rad of fin).
fn input_phasors(plant: &Plant, S: DMatrix<C64>, g: &DVector<C64>, omega: &DVector<C64>) -> [DVector<C64>; 2] {
    let (n, m) = (plant.A.nrows(), plant.B.ncols());
    let mut rhs = DMatrix::<C64>::zeros(n + m, 2);
    rhs.view_mut((n, 0), (m, 1)).copy_from(g);
    rhs.view_mut((0, 1), (n, 1)).copy_from(&(complex(&plant.D) * omega));
    rhs.view_mut((n, 1), (m, 1)).copy_from(&-(complex(&plant.Q) * omega));
    let solved = solve_without_rounding(S, &rhs);
    [0, 1].map(|k| match &solved {
        _ if rhs.column(k).iter().all(|z| *z == C64::new(0.0, 0.0)) => DVector::zeros(m),
        Some(x) => x.column(k).rows(n, m).into_owned(),
        None => DVector::from_element(m, C64::new(f64::INFINITY, 0.0)),
    })
}

/// The components j of ω that reach no output at w: the steady input that holds y = 0 against
/// ω = e_j alone is zero to rounding (S [X; U] = [D e_j; −Q e_j], [`solve_without_rounding`]), so
/// some X has (jwI − A) X = D e_j and C X = −Q e_j: C (jwI − A)⁻¹ D e_j + Q = 0 where A has no
/// eigenvalue at jw, and the observer's innovation is 0 whatever L ((jwI − A + LC) X = (D − LQ) e_j).
/// The system matrix stays regular where A has an eigenvalue at jw that ω's path does not pass (a
/// plant with an integrator; a test on (jwI − A)⁻¹ had missed it: review, 2026-12-08). None at a
/// transmission zero (S singular).
pub(crate) fn unreached(plant: &Plant, w: f64) -> Vec<usize> {
    let (n, k) = (plant.A.nrows(), plant.D.ncols());
    if k == 0 {
        return Vec::new();
    }
    let mut rhs = DMatrix::<C64>::zeros(n + plant.B.ncols(), k);
    rhs.view_mut((0, 0), (n, k)).copy_from(&complex(&plant.D));
    rhs.view_mut((n, 0), (plant.C.nrows(), k)).copy_from(&-complex(&plant.Q));
    let Some(x) = solve_without_rounding(system_matrix(plant, w), &rhs) else { return Vec::new() };
    (0..k)
        .filter(|&j| {
            rhs.column(j).iter().any(|z| z.norm() > 0.0)
                && x.column(j).rows(n, x.nrows() - n).iter().all(|z| z.norm() == 0.0)
        })
        .collect()
}

/// S⁻¹ rhs with every entry within rounding of |S⁻¹| |rhs| (the sum of its terms' magnitudes)
/// set to 0, what an exact zero computes to; the inverse is formed only where some entry is below
/// 1e-8 of its column's largest. `None` where S is singular or the solution not finite.
fn solve_without_rounding(S: DMatrix<C64>, rhs: &DMatrix<C64>) -> Option<DMatrix<C64>> {
    let dim = S.nrows();
    let lu = S.lu();
    let x = lu.solve(rhs).filter(|x| x.iter().all(|z| z.re.is_finite() && z.im.is_finite()))?;
    let small = x.column_iter().any(|c| {
        let top = c.iter().map(|z| z.norm()).fold(0.0, f64::max);
        c.iter().any(|z| z.norm() <= 1e-8 * top)
    });
    if !small {
        return Some(x);
    }
    let magnitudes = |M: &DMatrix<C64>| M.map(|z| z.norm());
    let scale = magnitudes(&lu.solve(&DMatrix::identity(dim, dim))?) * magnitudes(rhs);
    let rounding = ROUNDING_FACTOR * f64::EPSILON * (dim + 1) as f64;
    Some(x.zip_map(&scale, |z, s| if z.norm() <= rounding * s { C64::new(0.0, 0.0) } else { z }))
}

/// How many times ε·(dim + 1) of its terms' magnitudes an entry may be and still read as rounding
/// ([`solve_without_rounding`]).
const ROUNDING_FACTOR: f64 = 16.0;

/// |C (jwI − A)⁻¹ D W + Q W| per output; `None` where jw is within 1e-9 (‖A‖ + w) of an
/// eigenvalue of A, `eigs`.
fn forced_output(plant: &Plant, eigs: &[C64], w: f64, omega: &DVector<C64>) -> Option<Vec<f64>> {
    let jw = C64::new(0.0, w);
    if eigs.iter().any(|l| (jw - l).norm() <= 1e-9 * (plant.A.norm() + w)) {
        return None;
    }
    let DW = complex(&plant.D) * omega;
    let X = resolvent(&plant.A, w, &DMatrix::from_column_slice(DW.len(), 1, DW.as_slice()));
    let Y = complex(&plant.C) * X.column(0) + complex(&plant.Q) * omega;
    Some(Y.iter().map(|y| y.norm()).collect())
}

/// Advice for each input whose steady state exceeds its actuator limits: its RMS or its mean
/// (y = g cannot be held) or its range (the loop saturates at times in steady state).
fn beyond_limits(steady: &SteadyInput, actuator: &Actuator, inputs: &[String]) -> Vec<String> {
    let mut advice = Vec::new();
    for (i, input) in inputs.iter().enumerate().take(actuator.limits.len()) {
        let (rms, [low, high]) = (steady.rms[i], steady.range[i]);
        let (lower, upper) = (actuator.lower_limit(i), actuator.limits[i]);
        // A mean beyond one limit (a heater asked to cool on average) is as impossible as an RMS
        // beyond both: a clipped input cannot average it (review, 2026-12-08).
        let mean = steady.mean[i];
        let what = if rms > upper.max(-lower) || mean < lower || mean > upper {
            "exceeds it: tracking g and rejecting ω exactly is impossible with this actuator, whatever the design; ask less of the loop (fewer harmonics, smaller references) or a stronger actuator"
        } else if high > upper || low < lower {
            "exceeds it at its peaks: the loop saturates at times in steady state"
        } else {
            continue;
        };
        let symmetric = actuator.symmetric(i);
        let limit = if symmetric {
            format!("limit truth.u_max = {}", fmt_short(upper))
        } else {
            format!("range truth.u_min … u_max = {} … {}", fmt_short(lower), fmt_short(upper))
        };
        advice.push(format!(
            "{input}: the steady-state input (RMS {}, {}) against the actuator {limit} {what}",
            fmt_4(rms),
            if symmetric {
                format!("peak {}", fmt_4(steady.peak[i]))
            } else {
                format!("from {} to {}", fmt_4(low), fmt_4(high))
            },
        ));
    }
    advice
}

/// Advice for each harmonic of ω whose forced response stays within [`TAIL_BOUND`] of every
/// output's reference peak yet costs an input at least [`COSTLY_SHARE`] of its steady-state peak.
fn costly_harmonics(
    steady: &SteadyInput,
    reference: &Signal,
    (inputs, outputs): (&[String], &[String]),
    unit: TimeUnit,
) -> Vec<String> {
    let bounds: Vec<f64> = reference.components.iter().map(|c| TAIL_BOUND * c.peak()).collect();
    let mut advice = Vec::new();
    for t in steady.tones.iter().filter(|t| t.passable(&bounds)) {
        let Some(moved) = &t.disturbance_output else { continue };
        let costly: Vec<String> = (0..steady.peak.len())
            .filter(|&i| steady.peak[i].is_finite() && t.for_disturbance[i] > 0.0)
            .filter(|&i| t.for_disturbance[i] >= COSTLY_SHARE * steady.peak[i])
            .map(|i| {
                let share = 100.0 * t.for_disturbance[i] / steady.peak[i];
                format!(
                    "±{} of {} ({share:.0} % of its steady-state peak {})",
                    fmt_4(t.for_disturbance[i]),
                    inputs[i],
                    fmt_4(steady.peak[i])
                )
            })
            .collect();
        if costly.is_empty() {
            continue;
        }
        let (j, y) = moved.iter().enumerate().fold((0, 0.0), |best, (j, &y)| {
            if y / bounds[j] > best.1 / bounds[best.0] {
                (j, y)
            } else {
                best
            }
        });
        advice.push(format!(
            "ω's harmonic at {} rad/{unit} has a forced response (input held at 0) of at most {} at {} (within the tail bound {}: 1 % of the reference's peak), yet cancelling it takes {}; if the actuator should not follow it, let it pass: an actuator limit below that (u_limit of the automatic design) does so where the limit binds in steady state rather than in the transient, as do observer poles slow enough that the disturbance observer does not see it",
            fmt_4(t.frequency),
            fmt_4(y),
            outputs[j],
            fmt_4(bounds[j]),
            costly.join(", "),
        ));
    }
    advice
}

/// Where the steady state itself asks more of an input than the true actuator gives (`[truth]`
/// u_max): the plant needs that input for y = g whatever the controller, so no poles or μ meet the
/// tail bound. A heating plant asking 15 of a 12 drive had every candidate diverge through the clip
/// and was told to give slower poles or a smaller μ by hand (helper tryout, 2026-12-06); a ball on a
/// plate whose run diverged through a 0.3 V clip was told only of the clipping (2026-12-07).
pub(crate) fn saturation_advice(s: &crate::Scenario) -> Option<String> {
    let actuator = s.actuator.as_ref()?;
    let steady = s.steady_input();
    let over: Vec<String> = (0..actuator.limits.len())
        .filter_map(|i| {
            let (lower, upper) = (actuator.lower_limit(i), actuator.limits[i]);
            let fmt = crate::settings::fmt_4;
            let short = crate::settings::fmt_short;
            // A symmetric range is held to the peak magnitude, named as u_max's; another to each end.
            let [low, high] = if actuator.symmetric(i) { [-steady.peak[i], steady.peak[i]] } else { steady.range[i] };
            if high > upper {
                Some(format!("u_f,{} peaks at {} against truth.u_max[{i}] = {}", i + 1, fmt(high), short(upper)))
            } else {
                (low < lower)
                    .then(|| format!("u_f,{} falls to {} against truth.u_min[{i}] = {}", i + 1, fmt(low), short(lower)))
            }
        })
        .collect();
    (!over.is_empty()).then(|| {
        format!(
            "the steady state itself asks more than the true actuator gives ({}; the design report's steady-state section): the plant needs that input for y = g whatever the controller, so no poles or μ meet the tail bound, and the clip, which the method does not model, can drive the runs away; ask less of the loop (smaller references, a disturbance the actuator can hold) or widen the actuator's range (truth.u_max, u_min)",
            over.join(", ")
        )
    })
}

#[cfg(test)]
mod tests {
    use super::{C64, TAIL_BOUND};
    use crate::scenario::Scenario;

    /// A disturbance part that reaches no output is found where A has an eigenvalue at that
    /// frequency: an integrator beside a washout path P_ω(s) = −0.5 s/((s + 1)(s + 2)) (by hand:
    /// x₂ = ω/(s + 1), x₃ = x₂/(s + 2), y = x₁ − x₂/2 + x₃), zero at s = 0 where A is singular. The
    /// bias adds no excited direction (rank 4 of q = 5: the reference's tone and ω's 1 rad/s), where
    /// a test on (jwI − A)⁻¹ had found none and kept a direction of λ = 2.5e-26 (review,
    /// 2026-12-08); ω's tone reaches y and is kept.
    #[test]
    fn a_washout_beside_an_integrator_reaches_no_output_at_zero() {
        let s = Scenario::from_toml(
            "[plant]\nA = [[0.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 1.0, -2.0]]\nB = [[1.0], [1.0], [0.0]]\nC = [[1.0, -0.5, 1.0]]\nD = [[0.0], [1.0], [0.0]]\nQ = [[0.0]]\ndelays = [0.05]\n[design]\nobserver_poles = [-2.0, -3.0, -4.0]\nchannel_poles = [[-1.0]]\nreference_filter_poles = [[-1.0, -2.0]]\ndisturbance_filter_poles = [[-1.0, -2.0, -3.0]]\nmu = [1.0]\nbeta = 1.0\n[reference]\ncomponents = [ { harmonics = [{ amplitude = 1.0, frequency = 0.5 }] } ]\n[disturbance]\ncomponents = [ { bias = 0.5, harmonics = [{ amplitude = 0.3, frequency = 1.0 }] } ]\n",
        )
        .unwrap();
        assert!(s.plant.A.determinant() == 0.0, "A is singular at s = 0");
        assert_eq!((super::unreached(&s.plant, 0.0), super::unreached(&s.plant, 1.0)), (vec![0], vec![]));
        let d = s.design().unwrap();
        let c = &crate::averaged::Averaged::new(&d, &s.reference, &s.disturbance).channels[0];
        assert_eq!((c.excited().count(), d.q()), (4, 5), "{:?}", c.lambda);
    }

    /// Nomoto's ship (Fossen 2011, Mariner: T = 107.3 s, K = 0.185 /s) with a rudder servo of
    /// 2.5 s: ψ' = r, r' = −a r + b δ + d, δ' = −c δ + c u_f; a wave yaw moment d at 0.6 and
    /// 0.9 rad/s (amplitudes `waves`) and a course reference 0.1 + 0.2 sin(0.005 t).
    fn ship(waves: (f64, f64), u_max: Option<f64>) -> Scenario {
        let truth = u_max.map_or(String::new(), |u| format!("[truth]\nu_max = [{u}]\n"));
        Scenario::from_toml(&format!(
            "[plant]\nA = [[0.0, 1.0, 0.0], [0.0, -0.0093197, 0.0017241], [0.0, 0.0, -0.4]]\nB = [[0.0], [0.0], [0.4]]\n\
             C = [[1.0, 0.0, 0.0]]\nD = [[0.0], [1.0], [0.0]]\nQ = [[0.0]]\ndelays = [1.0]\ninputs = [\"delta_c\"]\noutputs = [\"psi\"]\n\
             [design]\nobserver_poles = [-1.0, -1.5, -2.0]\nchannel_poles = [[-0.5, -0.6, -0.7]]\n\
             reference_filter_poles = [[-0.005, -0.0075, -0.01]]\ndisturbance_filter_poles = [[-0.4, -0.5, -0.7, -1.0, -1.3]]\nmu = [1.0]\nbeta = 200.0\n\
             [reference]\ncomponents = [{{ bias = 0.1, harmonics = [{{ amplitude = 0.2, frequency = 0.005 }}] }}]\n\
             [disturbance]\ncomponents = [{{ bias = 5e-5, harmonics = [{{ amplitude = {}, frequency = 0.6 }}, {{ amplitude = {}, frequency = 0.9 }}] }}]\n{truth}",
            waves.0, waves.1
        ))
        .unwrap()
    }

    #[test]
    fn the_ships_steady_rudder_is_the_closed_form() {
        // y = ψ = g forces r = ψ', then δ = (r' + a r − d)/b and u_f = (δ' + c δ)/c, so at a
        // frequency w: |U| = |jw + c|/c · |(jw + a) R − W|/b with R = jw G. Biases: r = 0, so
        // δ = −d/b = u_f (the course's bias needs no rudder: ψ integrates r).
        let (a, b, c) = (0.0093197, 0.0017241, 0.4);
        let s = ship((2e-4, 1e-4), None);
        let st = s.steady_input();
        let servo = |w: f64| (w * w + c * c).sqrt() / c;
        let expected = [
            (0.0, 5e-5 / b, 0.0),
            (0.005, servo(0.005) * 0.005 * (0.005f64.powi(2) + a * a).sqrt() * 0.2 / b, 0.0),
            (0.6, servo(0.6) * 2e-4 / b, 2e-4),
            (0.9, servo(0.9) * 1e-4 / b, 1e-4),
        ];
        assert_eq!(st.tones.len(), 4);
        for (t, (w, u, d)) in st.tones.iter().zip(expected) {
            assert_eq!(t.frequency, w);
            // A 4×4 complex LU of entries ≤ 1: 1e-12 relative.
            assert!((t.amplitude[0] - u).abs() <= 1e-12 * u, "{w}: {} against {u}", t.amplitude[0]);
            // With the input held at 0 a wave turns ψ by d/(w |jw + a|); at w = 0 the integrator
            // makes it unbounded.
            match &t.disturbance_output {
                None => assert_eq!(w, 0.0),
                Some(y) if d > 0.0 => {
                    let want = d / (w * (w * w + a * a).sqrt());
                    assert!((y[0] - want).abs() <= 1e-12 * want, "{w}: {} against {want}", y[0]);
                }
                Some(y) => assert_eq!(y[0], 0.0),
            }
        }
        let rms = (expected[0].1.powi(2) + expected[1..].iter().map(|e| e.1 * e.1 / 2.0).sum::<f64>()).sqrt();
        assert!((st.rms[0] - rms).abs() <= 1e-12 * rms);
        // The peak: u_f(t) from the closed-form phasors (a sin(wt) is Re(−j a e^{jwt})), sampled
        // over the common period 2π/0.005 (0.6 and 0.9 are its 120th and 180th harmonics) every
        // 1e-3 rad of the fastest phase, the maximum then within 1.3e-7 relative of the true one;
        // below the sum of the amplitudes, which the phases never line up to.
        let j = C64::new(0.0, 1.0);
        let phasor = |w: f64, g: C64, d: C64| ((j * w + a) * j * w * g - d) / b * (j * w + c) / c;
        let waves = [
            (0.005, phasor(0.005, -j * 0.2, C64::new(0.0, 0.0))),
            (0.6, phasor(0.6, C64::new(0.0, 0.0), -j * 2e-4)),
            (0.9, phasor(0.9, C64::new(0.0, 0.0), -j * 1e-4)),
        ];
        let u = |t: f64| -5e-5 / b + waves.iter().map(|(w, p)| (p * (j * w * t).exp()).re).sum::<f64>();
        let period = std::f64::consts::TAU / 0.005;
        let samples = (period * 0.9 / 1e-3) as usize;
        let peak = (0..samples).map(|k| u(k as f64 * period / samples as f64).abs()).fold(0.0, f64::max);
        assert!((st.peak[0] - peak).abs() <= 2e-7 * peak, "{} against {peak}", st.peak[0]);
        let sum: f64 = expected.iter().map(|e| e.1).sum();
        assert!(peak < 0.99 * sum, "{peak} against the sum {sum}");
    }

    #[test]
    fn a_wave_that_barely_turns_the_ship_but_works_the_rudder_is_named() {
        // Each wave turns ψ by 5.6e-4 and 1.2e-4 rad, within 1 % of the course's peak 0.3, and
        // takes 55 % and 37 % of the rudder's steady-state peak.
        let advice = ship((2e-4, 1e-4), None).steady_input().advice;
        assert_eq!(advice.len(), 2, "{advice:?}");
        assert!(
            advice[0].contains("at 0.6 rad/s has a forced response (input held at 0) of at most 0.0005555 at psi")
                && advice[0].contains("±0.2091 of delta_c (55 %"),
            "{}",
            advice[0]
        );
        assert!(advice[1].contains("at 0.9 rad/s") && advice[1].contains("u_limit"), "{}", advice[1]);
        // A transmission zero at a frequency of g gets no such line (nor a finite peak): below.
        // Ten times the 0.6 rad/s wave turns ψ by 5.6e-3, beyond the bound 3e-3: worth its rudder;
        // the 0.9 rad/s wave's share then falls to 7 %, below the quarter.
        let advice = ship((2e-3, 1e-4), None).steady_input().advice;
        assert!(advice.is_empty(), "{advice:?}");
    }

    /// Both waves turn the ship within the course's tail bound (3e-3 rad): let pass, the rudder's
    /// steady state is the course's and the disturbance's bias, the peak of the same ship without
    /// the waves (another scenario's steady state); ten times the 0.6 rad/s wave is beyond the
    /// bound and stays in (its amplitude, as the full peak counts it, on top).
    #[test]
    fn the_peak_letting_harmless_waves_pass_is_that_without_them() {
        let bounds = [TAIL_BOUND * 0.3];
        let calm = ship((0.0, 0.0), None).steady_input().peak[0];
        let passing = ship((2e-4, 1e-4), None).steady_input().peak_letting_pass(&bounds)[0];
        assert!((passing - calm).abs() <= 1e-12 * calm, "{passing} against {calm}");
        let rough = ship((2e-3, 1e-4), None).steady_input();
        let kept_wave = rough.tones.iter().find(|t| t.frequency == 0.6).unwrap().amplitude[0];
        let passing = rough.peak_letting_pass(&bounds)[0];
        assert!((passing - (calm + kept_wave)).abs() <= 1e-12 * passing, "{passing} against {calm} + {kept_wave}");
        // Nothing to let pass: the peak itself.
        assert_eq!(ship((2e-3, 1e-4), None).steady_input().peak_letting_pass(&[0.0]), rough.peak);
    }

    #[test]
    fn a_steady_input_beyond_the_actuator_limit_is_named() {
        // RMS 0.1815, peak 0.381 (the closed form above).
        for (limit, says) in [(0.1, Some("exceeds it")), (0.3, Some("exceeds it at its peaks")), (0.4, None)] {
            let advice = ship((2e-4, 1e-4), Some(limit)).steady_input().advice;
            let on_limit: Vec<_> = advice.iter().filter(|a| a.contains("truth.u_max")).collect();
            match says {
                Some(text) => assert!(on_limit.len() == 1 && on_limit[0].contains(text), "{limit}: {advice:?}"),
                None => assert!(on_limit.is_empty(), "{limit}: {advice:?}"),
            }
        }
    }

    #[test]
    fn a_frequency_at_a_transmission_zero_is_named_impossible() {
        // G(s) = (s² + 1.69)/((s + 1)(s + 2)(s + 3)): zeros ±1.3j. A reference at 1.3 rad/s cannot
        // be tracked by any input; the LU solve had returned a finite 1.2e16. At 1.2 rad/s it can.
        let at = |w: f64| {
            Scenario::from_toml(&format!(
                "[plant]\nA = [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-6.0, -11.0, -6.0]]\nB = [[0.0], [0.0], [1.0]]\nC = [[1.69, 0.0, 1.0]]\n\
                 delays = [0.0]\n[design]\nobserver_poles = [-5.0, -6.0, -7.0]\nchannel_poles = [[-2.0]]\nreference_filter_poles = [[-1.0, -2.0]]\n\
                 mu = [1.0]\nbeta = 1.0\n[reference]\ncomponents = [{{ harmonics = [{{ amplitude = 1.0, frequency = {w} }}] }}]\n"
            ))
            .unwrap()
            .steady_input()
        };
        let st = at(1.3);
        assert!(
            st.tones[0].transmission_zero && st.peak[0] == f64::INFINITY && st.tones[0].amplitude[0] == f64::INFINITY
        );
        assert!(
            st.advice.len() == 1 && st.advice[0].starts_with("1.3 rad/s is a transmission zero of (A, B, C)"),
            "{:?}",
            st.advice
        );
        // |U| = |G(j1.2)|⁻¹ = |(j1.2 + 1)(j1.2 + 2)(j1.2 + 3)| / |1.69 − 1.44| (closed form).
        let st = at(1.2);
        let want = (1.0f64 + 1.44).sqrt() * (4.0f64 + 1.44).sqrt() * (9.0f64 + 1.44).sqrt() / 0.25;
        assert!(
            !st.tones[0].transmission_zero && (st.peak[0] - want).abs() <= 1e-12 * want,
            "{} against {want}",
            st.peak[0]
        );
        assert!(st.advice.is_empty(), "{:?}", st.advice);
    }
}
