//! Wall-time records of the steps of a computation (per-pass timings, the papers' tables).

use std::time::Instant;

/// Wall time of each step, in milliseconds, in the order the steps ran.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Timings(pub Vec<(String, f64)>);

impl Timings {
    /// Runs `f`, records its time under `name` and returns its result.
    pub fn time<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let out = f();
        self.push(name, start.elapsed().as_secs_f64() * 1e3);
        out
    }

    /// Records `ms` milliseconds under `name`.
    pub fn push(&mut self, name: &str, ms: f64) {
        self.0.push((name.to_string(), ms));
    }

    /// The time recorded under `name`.
    #[must_use]
    pub fn get(&self, name: &str) -> Option<f64> {
        self.0.iter().find(|(n, _)| n == name).map(|(_, t)| *t)
    }

    /// Sum of all steps.
    #[must_use]
    pub fn total(&self) -> f64 {
        self.0.iter().map(|(_, t)| t).sum()
    }
}
