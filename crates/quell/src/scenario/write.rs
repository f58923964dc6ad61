//! Scenarios back to TOML: the inverse of [`Scenario::from_toml`], in the format of
//! `examples/paper.toml`, so that `Scenario::from_toml(&s.to_toml())` gives `s` again.
//!
//! Numbers are written in Rust's shortest round-trip form, so every value survives exactly; in
//! exponent form below 1e-4 and from 1e15 on (`mu = 1e-11`, not `0.00000000001`).

use nalgebra::{Complex, DMatrix};
use toml::{Table, Value};

use super::{Noise, Scenario, ScenarioError, Simulation};
use crate::design::{DesignSpec, ObserverChoice};
use crate::plant::Plant;
use crate::settings::Method;
use crate::settings::TimeUnit;
use crate::signal::Signal;

impl Scenario {
    /// The scenario as a TOML document that [`Scenario::from_toml`] reads back to the same values.
    pub fn to_toml(&self) -> String {
        tidy(&toml::to_string(&self.to_table()).unwrap_or_default())
    }

    /// The scenario as a TOML table: `name`, `[plant]`, `[design]`, `[reference]`, `[disturbance]`
    /// (when k > 0), `[simulation]`, and `[noise]` and `[truth]` (when present; the truth in full).
    pub fn to_table(&self) -> Table {
        let mut doc = Table::new();
        if let Some(name) = &self.name {
            doc.insert("name".into(), Value::String(name.clone()));
        }
        let mut plant = plant_table(&self.plant);
        self.names.write(&mut plant);
        doc.insert("plant".into(), Value::Table(plant));
        doc.insert("design".into(), Value::Table(design_table(&self.design)));
        doc.insert("reference".into(), Value::Table(signal_table(&self.reference)));
        if !self.disturbance.components.is_empty() {
            doc.insert("disturbance".into(), Value::Table(signal_table(&self.disturbance)));
        }
        doc.insert("simulation".into(), Value::Table(simulation_table(&self.simulation)));
        if let Some(noise) = &self.noise {
            doc.insert("noise".into(), Value::Table(noise_table(noise)));
        }
        if let Some(truth) = &self.truth {
            let mut t = truth_table(truth);
            if let Some(a) = &self.actuator {
                t.insert("actuator_delays".into(), numbers(&a.delays));
                t.insert("u_max".into(), numbers(&a.limits));
                if let Some(lower) = &a.lower {
                    t.insert("u_min".into(), numbers(lower));
                }
            }
            doc.insert("truth".into(), Value::Table(t));
        }
        doc
    }
}

/// `text`, a scenario's TOML, with its `[design]` replaced by `design`'s ([`design_table`]) and
/// every other line as it was, comments included: what the automatic design writes. A `[design]`
/// that `text` leaves out is added. `Err` names the line `text` fails to parse at.
pub fn with_design(text: &str, design: &DesignSpec) -> Result<String, ScenarioError> {
    let mut doc: toml_edit::DocumentMut =
        text.parse().map_err(|e: toml_edit::TomlError| ScenarioError::new("", format!("not valid TOML: {e}")))?;
    let mut new = Table::new();
    new.insert("design".into(), Value::Table(design_table(design)));
    let mut new: toml_edit::DocumentMut = toml::to_string(&new)
        .unwrap_or_default()
        .parse()
        .map_err(|e: toml_edit::TomlError| ScenarioError::new("design", e.to_string()))?;
    short_floats(&mut new);
    let Some(toml_edit::Item::Table(mut table)) = new.as_table().get("design").cloned() else {
        return Err(ScenarioError::new("design", "the design did not render as a table"));
    };
    if let Some(old) = doc.get("design").and_then(toml_edit::Item::as_table) {
        // The comment above the old header, and its place among the tables.
        *table.decor_mut() = old.decor().clone();
        if let Some(position) = old.position() {
            table.set_position(Some(position));
        }
    }
    doc.insert("design", toml_edit::Item::Table(table));
    Ok(doc.to_string())
}

/// `text` (TOML from [`toml::to_string`]) with every finite float in [`short_float`]'s form.
fn tidy(text: &str) -> String {
    match text.parse::<toml_edit::DocumentMut>() {
        Ok(mut doc) => {
            short_floats(&mut doc);
            doc.to_string()
        }
        Err(_) => text.to_owned(),
    }
}

/// Every finite float of `doc` in [`short_float`]'s form, its decor kept.
fn short_floats(doc: &mut toml_edit::DocumentMut) {
    struct Floats;
    impl toml_edit::visit_mut::VisitMut for Floats {
        fn visit_value_mut(&mut self, node: &mut toml_edit::Value) {
            if let toml_edit::Value::Float(f) = node {
                let x = *f.value();
                if let (true, Ok(mut short)) = (x.is_finite(), short_float(x).parse::<toml_edit::Value>()) {
                    *short.decor_mut() = f.decor().clone();
                    *node = short;
                }
            }
            toml_edit::visit_mut::visit_value_mut(self, node);
        }
    }
    toml_edit::visit_mut::VisitMut::visit_document_mut(&mut Floats, doc);
}

/// x in its shortest round-trip digits: `0.05`, `100.0`, and in exponent form below 1e-4 and from
/// 1e15 on (`1e-8`, `2.5e20`), all valid TOML floats.
pub(crate) fn short_float(x: f64) -> String {
    if x == 0.0 || (1e-4..1e15).contains(&x.abs()) {
        format!("{x:?}")
    } else {
        format!("{x:e}")
    }
}

fn numbers(v: &[f64]) -> Value {
    Value::Array(v.iter().map(|&x| Value::Float(x)).collect())
}

fn matrix(M: &DMatrix<f64>) -> Value {
    Value::Array(M.row_iter().map(|r| Value::Array(r.iter().map(|&x| Value::Float(x)).collect())).collect())
}

/// `[plant]`: A, B, C, delays, x0, and D, Q when k > 0.
pub fn plant_table(p: &Plant) -> Table {
    let mut t = Table::new();
    t.insert("A".into(), matrix(&p.A));
    t.insert("B".into(), matrix(&p.B));
    t.insert("C".into(), matrix(&p.C));
    if p.k() > 0 {
        t.insert("D".into(), matrix(&p.D));
        t.insert("Q".into(), matrix(&p.Q));
    }
    t.insert("delays".into(), numbers(&p.delays));
    t.insert("x0".into(), numbers(p.x0.as_slice()));
    if p.xhat0.iter().any(|&v| v != 0.0) {
        t.insert("xhat0".into(), numbers(p.xhat0.as_slice()));
    }
    if p.time_unit != TimeUnit::Seconds {
        t.insert("time_unit".into(), Value::String(p.time_unit.symbol().into()));
    }
    t
}

/// `[truth]`'s table of a true plant: [`plant_table`] without `time_unit` (the truth is in the
/// design model's unit).
pub fn truth_table(p: &Plant) -> Table {
    let mut t = plant_table(p);
    t.remove("time_unit");
    t
}

/// A pole list in the file's form: a real pole as a number, a pair re ± i·im as `[re, im]` (written
/// once, for im > 0). Err with the first complex pole whose conjugate is not in the list, which the
/// file's form cannot express.
pub fn pole_list(poles: &[Complex<f64>]) -> Result<Value, Complex<f64>> {
    let mut out = Vec::new();
    let mut pending: Vec<Complex<f64>> = Vec::new();
    for &p in poles {
        if p.im == 0.0 {
            out.push(Value::Float(p.re));
        } else if let Some(i) = pending.iter().position(|&z| z == p.conj()) {
            let z = pending.swap_remove(i);
            out.push(Value::Array(vec![Value::Float(z.re), Value::Float(z.im.abs())]));
        } else {
            pending.push(p);
        }
    }
    match pending.first() {
        Some(&p) => Err(p),
        None => Ok(Value::Array(out)),
    }
}

/// [`pole_list`], with a pole that lacks its conjugate written as the pair `[re, |im|]`.
pub(crate) fn poles_value(poles: &[Complex<f64>]) -> Value {
    let mut closed = poles.to_vec();
    loop {
        match pole_list(&closed) {
            Ok(v) => return v,
            Err(p) => closed.push(p.conj()),
        }
    }
}

pub(crate) fn pole_lists(lists: &[Vec<Complex<f64>>]) -> Value {
    Value::Array(lists.iter().map(|p| poles_value(p)).collect())
}

/// `[design]`. A complex pole whose conjugate is missing (which no [`DesignSpec`] read from a file
/// has; [`pole_list`] finds them) is written as the pair.
pub fn design_table(d: &DesignSpec) -> Table {
    let mut t = Table::new();
    match &d.observer {
        ObserverChoice::Gain(L) => t.insert("observer_gain".into(), matrix(L)),
        ObserverChoice::Poles(p) => t.insert("observer_poles".into(), poles_value(p)),
    };
    t.insert("channel_poles".into(), pole_lists(&d.channel_poles));
    t.insert("reference_filter_poles".into(), pole_lists(&d.reference_filter_poles));
    if !d.disturbance_filter_poles.is_empty() {
        t.insert("disturbance_filter_poles".into(), pole_lists(&d.disturbance_filter_poles));
    }
    t.insert("mu".into(), numbers(&d.mu));
    t.insert("beta".into(), Value::Float(d.beta));
    t.insert("regressor_scaling".into(), Value::String(d.regressor_scaling.name().into()));
    for (key, sizes) in [("reference_sizes", &d.reference_sizes), ("disturbance_sizes", &d.disturbance_sizes)] {
        if !sizes.is_empty() {
            t.insert(key.into(), numbers(sizes));
        }
    }
    if let Some(sigma) = &d.relative_degrees {
        let sigma = sigma.iter().map(|&s| Value::Integer(i64::try_from(s).unwrap_or(i64::MAX))).collect();
        t.insert("relative_degrees".into(), Value::Array(sigma));
    }
    t
}

/// `[reference]` or `[disturbance]`: `components = [{ bias, harmonics = [...] }, ...]`.
pub fn signal_table(s: &Signal) -> Table {
    let components = s
        .components
        .iter()
        .map(|c| {
            let mut t = Table::new();
            t.insert("bias".into(), Value::Float(c.bias));
            let harmonics = c
                .harmonics
                .iter()
                .map(|h| {
                    let mut t = Table::new();
                    t.insert("amplitude".into(), Value::Float(h.amplitude));
                    t.insert("frequency".into(), Value::Float(h.frequency));
                    t.insert("phase".into(), Value::Float(h.phase));
                    Value::Table(t)
                })
                .collect();
            t.insert("harmonics".into(), Value::Array(harmonics));
            Value::Table(t)
        })
        .collect();
    Table::from_iter([("components".to_string(), Value::Array(components))])
}

fn simulation_table(s: &Simulation) -> Table {
    let mut t = Table::new();
    t.insert("t_end".into(), Value::Float(s.t_end));
    if s.output_step_given {
        t.insert("output_step".into(), Value::Float(s.output_step));
    }
    t.insert("rtol".into(), Value::Float(s.rtol));
    t.insert("atol".into(), Value::Float(s.atol));
    if let Some(T) = s.sample_time {
        t.insert("sample_time".into(), Value::Float(T));
    }
    // Absent means auto, so files that never chose a method are written as they were.
    if s.method != Method::Auto {
        t.insert("method".into(), Value::String(s.method.name().into()));
    }
    if s.precision != crate::controller::Precision::F64 {
        t.insert("precision".into(), Value::String(s.precision.name().into()));
    }
    t
}

fn noise_table(n: &Noise) -> Table {
    let mut t = Table::new();
    t.insert("std".into(), numbers(&n.std));
    // Seeds above i64::MAX cannot be written in TOML; from_toml reads none.
    t.insert("seed".into(), Value::Integer(i64::try_from(n.seed).unwrap_or(i64::MAX)));
    if let Some(b) = n.bandwidth {
        t.insert("bandwidth".into(), Value::Float(b));
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_floats_round_trip_in_the_form_a_person_writes() {
        for (x, text) in [
            (0.05, "0.05"),
            (100.0, "100.0"),
            (-2.5, "-2.5"),
            (0.0, "0.0"),
            (1e-4, "0.0001"),
            (1e-8, "1e-8"),
            (-1.5e-11, "-1.5e-11"),
            (1e15, "1e15"),
            (6.02e23, "6.02e23"),
            (5e-324, "5e-324"),
            (f64::MAX, "1.7976931348623157e308"),
        ] {
            assert_eq!(short_float(x), text);
            let doc: toml::Table = toml::from_str(&format!("x = {text}")).unwrap();
            assert_eq!(doc["x"].as_float().unwrap().to_bits(), x.to_bits(), "{text}");
        }
        let mut s = Scenario::from_toml(super::super::PAPER_EXAMPLE).unwrap();
        s.simulation.rtol = 1e-8;
        s.design.mu = vec![1e-11, 3.0];
        let text = s.to_toml();
        assert!(text.contains("rtol = 1e-8\n") && text.contains("mu = [1e-11, 3.0]"), "{text}");
        assert_eq!(Scenario::from_toml(&text).unwrap().to_table(), s.to_table());
    }

    #[test]
    fn a_design_replaces_the_old_one_and_every_other_line_stays() {
        let text = super::super::PAPER_EXAMPLE;
        let paper = Scenario::from_toml(text).unwrap();
        let mut design = paper.design.clone();
        design.mu = vec![2e-9, 0.25];
        design.beta = 0.5;
        let written = with_design(text, &design).unwrap();
        let back = Scenario::from_toml(&written).unwrap();
        assert_eq!(back.design, design);
        assert_eq!(Scenario { design: paper.design.clone(), ..back }.to_table(), paper.to_table());
        // The lines outside [design] (comments included) are the input's, in its order.
        let outside = |t: &str| {
            let (start, end) = (t.find("[design]").unwrap(), t.find("[reference]").unwrap());
            format!("{}{}", &t[..start], &t[end..])
        };
        assert_eq!(outside(&written), outside(text));
        assert!(written.contains("mu = [2e-9, 0.25]"), "{written}");
        // Without a [design], one is added (toml_edit places a table without a position after the
        // one before it: here [plant]); a file that is not TOML is an error.
        let start = text.find("[design]").unwrap();
        let end = text.find("[reference]").unwrap();
        let bare = format!("{}{}", &text[..start], &text[end..]);
        let added = with_design(&bare, &design).unwrap();
        assert_eq!(outside(&added), bare, "[design] goes after [plant]");
        assert_eq!(Scenario::from_toml(&added).unwrap().design, design);
        let e = with_design("A = [", &design).unwrap_err();
        assert!(e.to_string().contains("not valid TOML"), "{e}");
    }

    #[test]
    fn the_method_round_trips_and_auto_is_written_as_no_key() {
        let paper = Scenario::from_toml(super::super::PAPER_EXAMPLE).unwrap();
        assert!(!paper.to_toml().contains("method"), "an absent method stays absent");
        for method in [Method::Auto, Method::Explicit, Method::Implicit] {
            let mut s = paper.clone();
            s.simulation.method = method;
            let text = s.to_toml();
            let back = Scenario::from_toml(&text).unwrap();
            assert_eq!(back.simulation, s.simulation, "{text}");
            assert_eq!(back.to_toml(), text);
            let written = format!("method = \"{}\"", method.name());
            assert_eq!(text.contains(&written), method != Method::Auto, "{text}");
        }
        let explicit = super::super::PAPER_EXAMPLE.replacen("atol = 1e-9\n", "atol = 1e-9\nmethod = \"auto\"\n", 1);
        assert_eq!(Scenario::from_toml(&explicit).unwrap().to_toml(), paper.to_toml(), "\"auto\" is the default");
    }

    #[test]
    fn the_precision_round_trips_and_f64_is_written_as_no_key() {
        let paper = Scenario::from_toml(super::super::PAPER_EXAMPLE).unwrap();
        let mut s = paper.clone();
        s.simulation.sample_time = Some(1e-3);
        assert!(!s.to_toml().contains("precision"), "f64, the default, stays absent");
        s.simulation.precision = crate::controller::Precision::F32;
        let text = s.to_toml();
        assert!(text.contains("precision = \"f32\""), "{text}");
        assert_eq!(Scenario::from_toml(&text).unwrap().simulation, s.simulation);
    }

    #[test]
    fn every_example_round_trips() {
        for entry in std::fs::read_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples")).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "toml") {
                let s = Scenario::from_path(&path).unwrap();
                let text = s.to_toml();
                let back = Scenario::from_toml(&text).unwrap_or_else(|e| panic!("{}: {e}\n{text}", path.display()));
                assert_eq!(back.to_toml(), text, "{}", path.display());
                assert_eq!(back.plant, s.plant);
                assert_eq!(back.design, s.design);
                assert_eq!(back.reference, s.reference);
                assert_eq!(back.disturbance, s.disturbance);
                assert_eq!(back.simulation, s.simulation);
                assert_eq!(back.noise, s.noise);
                assert_eq!(back.name, s.name);
                assert_eq!(back.truth, s.truth);
            }
        }
    }

    #[test]
    fn truth_round_trips() {
        let text = format!("{}\n[truth]\ndelays = [1.1, 2.9]\nx0 = [0.5, 0.0, 0.0]\n", crate::scenario::PAPER_EXAMPLE);
        let s = Scenario::from_toml(&text).unwrap();
        let back = Scenario::from_toml(&s.to_toml()).unwrap();
        assert_eq!(back.truth, s.truth);
        assert_eq!(back.truth.unwrap().delays, vec![1.1, 2.9]);
    }

    #[test]
    fn unpaired_complex_pole_has_no_file_form() {
        let p = [Complex::new(-1.0, 2.0), Complex::new(-3.0, 0.0)];
        assert_eq!(pole_list(&p), Err(p[0]));
        let q = [Complex::new(-1.0, -2.0), Complex::new(-3.0, 0.0), Complex::new(-1.0, 2.0)];
        assert_eq!(pole_list(&q).unwrap().to_string(), "[-3.0, [-1.0, 2.0]]");
    }

    #[test]
    fn an_unpaired_complex_pole_is_written_as_its_pair() {
        let p = [Complex::new(-1.0, -2.0), Complex::new(-3.0, 0.0), Complex::new(-4.0, 1.0), Complex::new(-4.0, -1.0)];
        assert_eq!(poles_value(&p).to_string(), "[-3.0, [-4.0, 1.0], [-1.0, 2.0]]");
    }
}
