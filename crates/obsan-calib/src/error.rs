//! The calibration's typed errors. `Display` is the exact text the CLI prints
//! (its tests compare the texts), so a variant's message never changes with
//! the refactoring that introduced it.

use obsan_fit::FitError;
use std::fmt;

/// What went wrong in the simulator, an estimator or the calibration pipeline.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum CalibError {
    /// The data do not determine the estimate (DET, LS, section V-C's
    /// combination, a loop not covered): the message says which and why.
    Degenerate(String),
    /// A column the estimator reads is absent (`no column 'x'`).
    MissingColumn(String),
    /// The CEKF's input column is absent.
    MissingInput(String),
    /// The CEKF's output column is absent.
    MissingOutput(String),
    /// The CEKF's state or covariance became non-finite at time `t`.
    FilterDiverged { t: f64 },
    /// An error in one named trajectory.
    Trajectory {
        name: String,
        source: Box<CalibError>,
    },
    /// A trajectory's meta.json has no `q` (the commanded ratio, eq. 17).
    NoQ { trajectory: String },
    /// `ml` was asked for without the model.
    NoModel,
    /// `cekf` was asked for without the bearing noise.
    NoBearingNoise,
    /// Fewer given CEKF start states than trajectories.
    NoCekfStart { trajectory: String },
    /// The maximum-likelihood fit failed.
    Ml(FitError),
    /// The ML fit ran but returned no estimate (for the CRLB).
    NoMlEstimate,
    /// The CRLB could not be computed.
    Crlb(FitError),
    /// `--speed-profile` text not understood: the message names the form.
    SpeedProfile(String),
    /// `--effect` names no known effect.
    UnknownEffect(String),
    /// A wheel radius, the wheel base or rho is not positive.
    RobotNotPositive,
    /// The feature starts inside the robot (`d0 <= rho`).
    FeatureInsideRobot { d0: f64, rho: f64 },
    /// The sample rates are not positive or the encoder is slower than the camera.
    Rates,
    /// A simulated circle is too straight to close a loop in `max_duration`.
    NoLoop {
        q: Option<f64>,
        turned: f64,
        max_duration: f64,
        ratio: f64,
    },
    /// A simulated trajectory would have fewer bearings than a dataset needs.
    TooFewBearings {
        trajectory: String,
        bearings: usize,
        duration: f64,
        needed: usize,
    },
}

impl fmt::Display for CalibError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use CalibError::*;
        match self {
            Degenerate(m) | SpeedProfile(m) => f.write_str(m),
            MissingColumn(c) => write!(f, "no column '{c}'"),
            MissingInput(c) => write!(f, "no input column '{c}'"),
            MissingOutput(c) => write!(f, "no output column '{c}'"),
            FilterDiverged { t } => write!(f, "the filter diverged at t = {t}"),
            Trajectory { name, source } => write!(f, "trajectory '{name}': {source}"),
            NoQ { trajectory } => write!(
                f,
                "trajectory '{trajectory}': no q in its meta.json (the commanded wheel-speed ratio of the circle, eq. 17)"
            ),
            NoModel => f.write_str("ml needs the model (calib.sys)"),
            NoBearingNoise => f.write_str(
                "cekf needs the bearing noise: give it in dataset.json (noise.beta) or use ls/ml",
            ),
            NoCekfStart { trajectory } => {
                write!(f, "no CEKF initial state for trajectory {trajectory}")
            }
            Ml(e) => write!(f, "maximum likelihood failed: {e}"),
            NoMlEstimate => f.write_str("maximum likelihood gave no estimate"),
            Crlb(e) => write!(f, "{e}"),
            UnknownEffect(name) => write!(
                f,
                "unknown effect '{name}' (known: time_offset, bearing_scale, bearing_distortion, wheel_slip, radius_change, bearing_bias)"
            ),
            RobotNotPositive => f.write_str("wheel radii, wheel base and rho must be positive"),
            FeatureInsideRobot { d0, rho } => write!(
                f,
                "the initial distance d0 = {d0} must exceed rho = {rho} (the feature would be inside the robot)"
            ),
            Rates => f.write_str(
                "rates must be positive, the encoder rate at least the bearing rate",
            ),
            NoLoop {
                q,
                turned,
                max_duration,
                ratio,
            } => {
                let qs = q.map_or(String::new(), |q| format!("q = {q} "));
                write!(
                    f,
                    "degenerate trajectory: {qs}turned only {turned:.3} rad in {max_duration} s (q = rR/rL = {ratio:.4} is a straight line); no full loop"
                )
            }
            TooFewBearings {
                trajectory,
                bearings,
                duration,
                needed,
            } => write!(
                f,
                "trajectory {trajectory}: only {bearings} bearings in its {duration:.1} s, and a dataset needs at least {needed} per trajectory: raise the bearing rate (or --bearings)"
            ),
        }
    }
}

impl std::error::Error for CalibError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            CalibError::Trajectory { source, .. } => Some(source.as_ref()),
            CalibError::Ml(e) | CalibError::Crlb(e) => Some(e),
            _ => None,
        }
    }
}

impl CalibError {
    /// `self` in the named trajectory.
    pub fn in_trajectory(self, name: &str) -> CalibError {
        CalibError::Trajectory {
            name: name.to_string(),
            source: Box::new(self),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::CalibError;
    use crate::{calibrate, simulate, CalibrateOptions, Method, Robot, SimOptions, SpeedProfile};

    #[test]
    fn simulator_options_give_their_variants() {
        let bad_robot = SimOptions {
            robot: Robot {
                rho: 0.0,
                ..Robot::default()
            },
            ..SimOptions::default()
        };
        assert_eq!(
            simulate(&bad_robot).unwrap_err(),
            CalibError::RobotNotPositive
        );
        let inside = SimOptions {
            d0: 0.01,
            ..SimOptions::default()
        };
        match simulate(&inside).unwrap_err() {
            CalibError::FeatureInsideRobot { d0, rho } => {
                assert_eq!((d0, rho), (0.01, Robot::default().rho))
            }
            e => panic!("{e:?}"),
        }
        let slow_encoder = SimOptions {
            encoder_rate: 1.0,
            bearing_rate: 10.0,
            ..SimOptions::default()
        };
        assert_eq!(simulate(&slow_encoder).unwrap_err(), CalibError::Rates);
        // q = rR/rL drives a straight line: the loop never closes.
        let r = Robot::default();
        let straight = SimOptions {
            q: vec![r.r_right / r.r_left],
            max_duration: 5.0,
            ..SimOptions::default()
        };
        let e = simulate(&straight).unwrap_err();
        assert!(matches!(e, CalibError::NoLoop { max_duration, .. } if max_duration == 5.0));
        assert!(
            e.to_string().starts_with("degenerate trajectory: q = "),
            "{e}"
        );
        let few = SimOptions {
            q: vec![0.0],
            bearings: Some(3),
            ..SimOptions::default()
        };
        match simulate(&few).unwrap_err() {
            CalibError::TooFewBearings { bearings, .. } => assert!(bearings < 10),
            e => panic!("{e:?}"),
        }
    }

    #[test]
    fn parsers_and_setters_give_their_variants() {
        let e = "sine:2:10".parse::<SpeedProfile>().unwrap_err();
        assert!(matches!(&e, CalibError::SpeedProfile(m) if m.starts_with("sine:2:10: ")));
        let mut o = SimOptions::default();
        let e = o.effects.set("wobble", 1.0).unwrap_err();
        assert_eq!(e, CalibError::UnknownEffect("wobble".into()));
        assert!(e
            .to_string()
            .starts_with("unknown effect 'wobble' (known: "));
    }

    #[test]
    fn pipeline_errors_name_the_trajectory() {
        let (mut data, _) = simulate(&SimOptions::default()).unwrap();
        // ml without the model.
        let o = CalibrateOptions::for_dataset(&data, Method::Ml);
        assert_eq!(calibrate(&data, None, &o).unwrap_err(), CalibError::NoModel);
        // A trajectory without q.
        data.trajectories[1].meta.remove("q");
        let name = data.trajectories[1].name.clone();
        let o = CalibrateOptions::for_dataset(&data, Method::Ls);
        assert_eq!(
            calibrate(&data, None, &o).unwrap_err(),
            CalibError::NoQ { trajectory: name }
        );
        // A missing output column, wrapped in its trajectory.
        let (data, _) = simulate(&SimOptions::default()).unwrap();
        let o = CalibrateOptions {
            output: "gamma".into(),
            ..CalibrateOptions::for_dataset(&data, Method::Ls)
        };
        let e = calibrate(&data, None, &o).unwrap_err();
        match &e {
            CalibError::Trajectory { name, source } => {
                assert_eq!(name, &data.trajectories[0].name);
                assert_eq!(**source, CalibError::MissingColumn("gamma".into()));
            }
            e => panic!("{e:?}"),
        }
        assert_eq!(
            e.to_string(),
            format!(
                "trajectory '{}': no column 'gamma'",
                data.trajectories[0].name
            )
        );
        assert!(std::error::Error::source(&e).is_some());
    }
}
