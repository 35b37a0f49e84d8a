//! What the benchmark examples share: their command-line flags and the adapter header.
// Each example uses a part of it.
#![allow(dead_code)]

use gi_core::scene::desc::LightDesc;
use gi_core::scene::SceneUpdate;
use gi_core::Scene;
use std::error::Error;

/// The command line: `--runs N`, `--quick`, `--FLAG VALUE`.
pub struct Args(Vec<String>);

impl Args {
    pub fn get() -> Self {
        Args(std::env::args().collect())
    }

    /// The value after `flag`, if given.
    pub fn value(&self, flag: &str) -> Option<&str> {
        let i = self.0.iter().position(|a| a == flag)?;
        self.0.get(i + 1).map(String::as_str)
    }

    /// The values after every `flag` (a repeatable flag).
    pub fn values(&self, flag: &str) -> Vec<&str> {
        self.0
            .windows(2)
            .filter(|w| w[0] == flag)
            .map(|w| w[1].as_str())
            .collect()
    }

    /// Timed runs per measurement: `--runs N`, else `default`.
    pub fn runs(&self, default: usize) -> Result<usize, Box<dyn Error>> {
        match self.0.iter().position(|a| a == "--runs") {
            Some(_) => Ok(self
                .value("--runs")
                .ok_or("--runs needs a value")?
                .parse()?),
            None => Ok(default),
        }
    }

    /// `--quick`: the smallest configurations only.
    pub fn quick(&self) -> bool {
        self.flag("--quick")
    }

    /// Whether `flag` is given (a flag without a value).
    pub fn flag(&self, flag: &str) -> bool {
        self.0.iter().any(|a| a == flag)
    }
}

/// Prints the adapter (the first four lines of its report, on one line) and a blank line.
pub fn print_adapter() -> Result<(), Box<dyn Error>> {
    let report = gi_core::gpu::adapter_report(None)?;
    println!(
        "{}\n",
        report.lines().take(4).collect::<Vec<_>>().join("; ")
    );
    Ok(())
}

/// The median of timings (the upper one of an even count).
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Light 0 nudged by `t` (metres along x).
pub fn nudge(scene: &Scene, t: f32) -> SceneUpdate {
    let mut light = scene.light_desc(0).expect("a light");
    match &mut light {
        LightDesc::Point { position, .. } | LightDesc::Spot { position, .. } => position[0] += t,
        // A distant light turns instead.
        LightDesc::Directional { direction, .. } => direction[0] += t,
    }
    SceneUpdate::Light { index: 0, light }
}

pub mod instancing;
