//! `Design::new` of large plants: the seeded plant of `scripts/large_plant.py` (same generator, same
//! numbers), n states, two inputs and outputs, A upper triangular plus its diagonal, so that its
//! eigenvalues are known exactly. The observer poles lie between the plant's eigenvalues
//! (`between`) or on them (`at eigenvalues`, where every admissible space of the pole placement
//! is taken at a singular A − λ I).
//!
//! `cargo bench -p quell --bench design -- --warm-up-time 1 --measurement-time 3` (criterion takes
//! at least 10 samples: the n = 400 cases run for about a minute and a half).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use quell::Scenario;

/// Knuth's MMIX LCG, its top 53 bits as a value in [−1/2, 1/2) (as the script).
struct Lcg(u64);

impl Lcg {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}

fn matrix(rows: &[Vec<f64>]) -> String {
    let row = |r: &Vec<f64>| format!("[{}]", r.iter().map(|x| format!("{x:e}")).collect::<Vec<_>>().join(", "));
    format!("[{}]", rows.iter().map(row).collect::<Vec<_>>().join(", "))
}

/// The scenario `python3 scripts/large_plant.py n [--poles plant]` writes.
fn large_plant(n: usize, at_eigenvalues: bool) -> Scenario {
    let mut rng = Lcg(1);
    let mut a = vec![vec![0.0; n]; n];
    for (r, row) in a.iter_mut().enumerate() {
        for (c, x) in row.iter_mut().enumerate().skip(r) {
            let u = rng.uniform();
            *x = if r == c { -1.0 - 0.05 * r as f64 + 0.02 * u } else { 0.02 * u };
        }
    }
    let b: Vec<Vec<f64>> = (0..n).map(|_| vec![rng.uniform(), rng.uniform()]).collect();
    let c: Vec<Vec<f64>> = (0..2).map(|j| b.iter().map(|row| row[j]).collect()).collect();
    let poles: Vec<String> = (0..n)
        .map(|j| if at_eigenvalues { a[j][j] } else { -1.025 - 0.05 * j as f64 })
        .map(|p| format!("{p:e}"))
        .collect();
    let text = format!(
        "[plant]\nA = {}\nB = {}\nC = {}\ndelays = [0.0, 0.0]\n[design]\nobserver_poles = [{}]\n\
         channel_poles = [[-2.0], [-3.0]]\nreference_filter_poles = [[-1.0], [-1.0]]\nmu = [1.0, 1.0]\nbeta = 1.0\n\
         [reference]\ncomponents = [{{ bias = 1.0 }}, {{ bias = 1.0 }}]\n",
        matrix(&a),
        matrix(&b),
        matrix(&c),
        poles.join(", ")
    );
    Scenario::from_toml(&text).expect("the generated scenario reads")
}

fn designs(c: &mut Criterion) {
    let mut group = c.benchmark_group("design");
    group.sample_size(10);
    for (n, at_eigenvalues) in [(200, false), (200, true), (400, false), (400, true)] {
        let scenario = large_plant(n, at_eigenvalues);
        scenario.design().expect("the large plant's design succeeds");
        let poles = if at_eigenvalues { "at eigenvalues" } else { "between" };
        group.bench_function(BenchmarkId::new(format!("n={n}"), poles), |bench| {
            bench.iter(|| scenario.design().expect("design"))
        });
    }
    group.finish();
}

criterion_group!(benches, designs);
criterion_main!(benches);
