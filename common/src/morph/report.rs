//! The typed report every morph fills ([`MorphReport`]): how the method
//! ended, its iterations and residuals, time per stage and memory, plus the
//! method's own figures.

use serde::Serialize;
use serde::ser::SerializeMap;
use std::time::Instant;

/// How a morph's construction ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// A direct method finished (a blend, a linear solve, a decomposition):
    /// there is nothing to converge.
    Direct,
    /// An iterative method met its stopping test.
    Converged,
    /// An iterative method stopped making progress before its stopping test
    /// (e.g. the T-spline's curvature speed far from the target).
    Stalled,
    /// An iterative method reached its iteration or step cap first.
    IterationCap,
}

impl Outcome {
    /// Whether the method reached its goal ([`Outcome::Direct`] or
    /// [`Outcome::Converged`]).
    pub fn succeeded(self) -> bool {
        matches!(self, Outcome::Direct | Outcome::Converged)
    }
}

/// A residual with its meaning and unit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Residual {
    /// What was measured, e.g. `"RMS target distance at the surface"`.
    pub what: &'static str,
    /// The value.
    pub value: f64,
    /// Its unit, e.g. `"voxels"`, `"domain units"`, `"relative"`.
    pub unit: &'static str,
}

/// Wall time of one stage of a morph's construction.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StageTime {
    /// The stage, e.g. `"distance volumes"`, `"evolution"`.
    pub stage: String,
    /// Seconds of wall time.
    pub seconds: f64,
}

/// A value of a method-specific figure.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Value {
    /// A count or index.
    Int(i64),
    /// A measurement.
    Float(f64),
    /// A yes/no fact.
    Bool(bool),
    /// A name or short description.
    Text(String),
}

macro_rules! value_from {
    ($($t:ty => $v:ident $(as $c:ty)?),*) => {$(
        impl From<$t> for Value {
            fn from(x: $t) -> Self {
                Value::$v(x $(as $c)?)
            }
        }
    )*};
}
value_from!(i64 => Int, i32 => Int as i64, u32 => Int as i64, usize => Int as i64, f64 => Float,
    f32 => Float as f64, bool => Bool, String => Text);

impl From<&str> for Value {
    fn from(x: &str) -> Self {
        Value::Text(x.to_string())
    }
}

/// Method-specific figures, in the order they were added; serialized as a
/// JSON object.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Details(Vec<(&'static str, Value)>);

impl Details {
    /// The figures as (name, value) pairs.
    pub fn iter(&self) -> impl Iterator<Item = (&'static str, &Value)> {
        self.0.iter().map(|(k, v)| (*k, v))
    }

    /// The value named `name`.
    pub fn get(&self, name: &str) -> Option<&Value> {
        self.0.iter().find(|(k, _)| *k == name).map(|(_, v)| v)
    }

    /// Number of figures.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

impl Serialize for Details {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }
}

/// What a user needs to trust a morph: the outcome, iterations, residuals,
/// conditioning, time per stage, memory, warnings and the method's own
/// figures. Built with [`MorphReport::new`] and its `with_*` methods;
/// `report.json` carries it under `"morph"`.
///
/// ```
/// use isomorph_common::{MorphReport, Outcome, Residual};
///
/// let report = MorphReport::new("level-set", Outcome::Converged)
///     .with_iterations(120)
///     .with_residual(Residual { what: "RMS target distance", value: 0.008, unit: "voxels" })
///     .with_stage("evolution", 0.4)
///     .with_detail("solver", "sparse field");
/// assert!(report.converged);
/// assert_eq!(report.stage_seconds("evolution"), Some(0.4));
/// ```
#[derive(Debug, Clone, PartialEq, Serialize)]
#[non_exhaustive]
pub struct MorphReport {
    /// The method's name ([`crate::Morph::method`]).
    pub method: &'static str,
    /// How construction ended.
    pub outcome: Outcome,
    /// [`Outcome::succeeded`]: the method reached its goal.
    pub converged: bool,
    /// Iterations or steps of an iterative method.
    pub iterations: Option<usize>,
    /// The final residual or fit error.
    pub residual: Option<Residual>,
    /// Reciprocal condition estimate of a linear system, when one is solved.
    pub rcond: Option<f64>,
    /// Wall time per stage of construction, in order.
    pub stages: Vec<StageTime>,
    /// Heap bytes the morph keeps to make frames.
    pub stored_bytes: usize,
    /// Largest working memory of construction (bytes), as estimated by the
    /// method from its own allocations.
    pub peak_bytes: Option<usize>,
    /// Things a user should know (e.g. an open input mesh, a small
    /// unreachable part of the target).
    pub warnings: Vec<String>,
    /// The method's own figures.
    pub details: Details,
}

impl MorphReport {
    /// A report of `method` that ended with `outcome`.
    pub fn new(method: &'static str, outcome: Outcome) -> Self {
        Self {
            method,
            outcome,
            converged: outcome.succeeded(),
            iterations: None,
            residual: None,
            rcond: None,
            stages: Vec::new(),
            stored_bytes: 0,
            peak_bytes: None,
            warnings: Vec::new(),
            details: Details::default(),
        }
    }

    /// With the iteration count.
    pub fn with_iterations(mut self, n: usize) -> Self {
        self.iterations = Some(n);
        self
    }

    /// With the final residual.
    pub fn with_residual(mut self, r: Residual) -> Self {
        self.residual = Some(r);
        self
    }

    /// With a reciprocal condition estimate.
    pub fn with_rcond(mut self, rcond: f64) -> Self {
        self.rcond = Some(rcond);
        self
    }

    /// With one more stage time.
    pub fn with_stage(mut self, stage: impl Into<String>, seconds: f64) -> Self {
        self.stages.push(StageTime { stage: stage.into(), seconds });
        self
    }

    /// With the stage times of `stages`.
    pub fn with_stages(mut self, stages: Stages) -> Self {
        self.stages.extend(stages.0);
        self
    }

    /// With the bytes kept for frames and the estimated peak.
    pub fn with_memory(mut self, stored: usize, peak: Option<usize>) -> Self {
        self.stored_bytes = stored;
        self.peak_bytes = peak;
        self
    }

    /// With the warnings `w` appended.
    pub fn with_warnings(mut self, w: impl IntoIterator<Item = String>) -> Self {
        self.warnings.extend(w);
        self
    }

    /// With one more method-specific figure.
    pub fn with_detail(mut self, name: &'static str, value: impl Into<Value>) -> Self {
        self.details.0.push((name, value.into()));
        self
    }

    /// Seconds spent in `stage` (summed when it occurs more than once).
    pub fn stage_seconds(&self, stage: &str) -> Option<f64> {
        let mut found = self.stages.iter().filter(|s| s.stage == stage).peekable();
        found.peek()?;
        Some(found.map(|s| s.seconds).sum())
    }

    /// Seconds of all stages.
    pub fn total_seconds(&self) -> f64 {
        self.stages.iter().map(|s| s.seconds).sum()
    }
}

/// A stopwatch over consecutive stages: [`Stages::lap`] closes the current
/// stage under a name and starts the next.
#[derive(Debug, Clone)]
pub struct Stages(Vec<StageTime>, Instant);

impl Stages {
    /// Starts the first stage now.
    pub fn start() -> Self {
        Self(Vec::new(), Instant::now())
    }

    /// Ends the running stage as `stage` and starts the next one.
    pub fn lap(&mut self, stage: &str) {
        let now = Instant::now();
        self.0.push(StageTime { stage: stage.to_string(), seconds: (now - self.1).as_secs_f64() });
        self.1 = now;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn report_serializes_with_details_as_an_object() {
        let mut stages = Stages::start();
        stages.lap("a");
        stages.lap("b");
        let r = MorphReport::new("x", Outcome::Stalled)
            .with_stages(stages)
            .with_detail("n", 3usize)
            .with_detail("kind", "sparse");
        assert!(!r.converged);
        assert_eq!(r.stages.len(), 2);
        let json = serde_json::to_value(&r).unwrap();
        assert_eq!(json["outcome"], "stalled");
        assert_eq!(json["details"]["n"], 3);
        assert_eq!(json["details"]["kind"], "sparse");
        assert!(r.stage_seconds("c").is_none());
    }
}
