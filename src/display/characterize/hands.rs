//! Where a simulated meter in front of a simulated monitor is: facing the screen, on its
//! white tile or capped. A real operator moves the instrument when the session asks for a
//! calibration and aims it at the screen again afterwards; these hands do the same for a
//! simulated one, so an i1Pro's dark calibration is taken on its tile and not on whatever
//! the monitor shows (which would subtract the monitor's black from every reading and call
//! the black itself too dark).

use std::sync::{Arc, RwLock};

use metamer_drivers::world::{View, World};
use metamer_drivers::CalibrationCondition;

use crate::session::{
    Answer, Operator, OperatorError, PlacementReadings, Recheck, AIM_AT_SCREEN_AGAIN,
};

/// What the simulated meter sees: the screen's light, or its tile or cap while a
/// calibration needs them.
pub struct Hands {
    screen: Arc<dyn World>,
    /// None while the meter faces the screen.
    placed: RwLock<Option<View>>,
}

impl Hands {
    pub fn new(screen: Arc<dyn World>) -> Arc<Hands> {
        Arc::new(Hands {
            screen,
            placed: RwLock::new(None),
        })
    }

    fn place(&self, view: Option<View>) {
        *self.placed.write().unwrap_or_else(|e| e.into_inner()) = view;
    }

    /// Acts on a session prompt as an operator's hands would: onto the tile, under the cap,
    /// or back at the screen.
    fn act(&self, prompt: &str) {
        if prompt.ends_with(&CalibrationCondition::OnWhiteTile.prompt()) {
            self.place(Some(View::WhiteTile));
        } else if prompt.ends_with(&CalibrationCondition::SensorCapped.prompt()) {
            self.place(Some(View::Capped));
        } else if prompt.ends_with(AIM_AT_SCREEN_AGAIN)
            || prompt.ends_with(&CalibrationCondition::OnTarget.prompt())
        {
            self.place(None);
        }
    }
}

impl World for Hands {
    fn view(&self) -> View {
        match &*self.placed.read().unwrap_or_else(|e| e.into_inner()) {
            Some(view) => view.clone(),
            None => self.screen.view(),
        }
    }
}

/// The session's operator with the simulated meter's hands: every prompt moves the meter
/// first, then goes to the operator as it would without them.
pub struct HandsOperator<'a> {
    pub hands: Arc<Hands>,
    pub inner: &'a mut dyn Operator,
}

impl Operator for HandsOperator<'_> {
    fn ask(&mut self, prompt: &str) -> Result<Answer, OperatorError> {
        self.hands.act(prompt);
        self.inner.ask(prompt)
    }

    fn ask_placement(
        &mut self,
        what: &str,
        readings: PlacementReadings,
    ) -> Result<Answer, OperatorError> {
        self.hands.act(what);
        self.inner.ask_placement(what, readings)
    }

    fn recheck(&mut self, why: &str) -> Result<Recheck, OperatorError> {
        self.inner.recheck(why)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use metamer_drivers::world::SharedWorld;

    /// The meter sees the screen until a calibration puts it on its tile, and the screen
    /// again once it is aimed back.
    #[test]
    fn a_calibration_prompt_moves_the_meter_and_the_re_aim_brings_it_back() {
        let screen = Arc::new(SharedWorld::new([1.0, 2.0, 3.0]));
        let hands = Hands::new(screen);
        let lit = View::xyz([1.0, 2.0, 3.0].into());
        assert_eq!(hands.view(), lit);
        let mut quiet = crate::session::ScriptedOperator::confirming();
        let mut op = HandsOperator {
            hands: hands.clone(),
            inner: &mut quiet,
        };
        let tile = format!(
            "meter instrument (i1pro), emissive calibration: {}",
            CalibrationCondition::OnWhiteTile.prompt()
        );
        assert_eq!(op.ask(&tile).unwrap(), Answer::Confirmed);
        assert_eq!(hands.view(), View::WhiteTile);
        op.ask(&format!("meter instrument (i1pro): {AIM_AT_SCREEN_AGAIN}"))
            .unwrap();
        assert_eq!(hands.view(), lit);
        assert_eq!(quiet.prompts.len(), 2);
    }

    /// `characterize` with a simulated i1Pro on every simulated monitor: its dark is taken
    /// on its tile, so each black is read as the preset's (ideal-crt 0.05, ips-lcd 0.22,
    /// wide-gamut-ccfl 0.40 cd/m²), not "too dark"; the CRT's, too dim for one reading, is
    /// read six times. Within 5σ of the simulated unit's own noise at 2 s (0.013 cd/m²).
    #[test]
    fn an_i1pro_characterizes_every_simulated_monitor_black_included() {
        use crate::display::characterize::{
            characterize, Attend, Listener, Outcome, PlanOptions, Request, SimulatedMeter,
        };
        use crate::display::ModelKind;
        use crate::rig::{Preset, ScreenSpec};
        use crate::session::{NoProgress, ProgressSink, RunOptions};

        struct Quiet(NoProgress);
        impl Listener for Quiet {
            fn note(&mut self, _: &str) {}
            fn warning(&mut self, _: &str) {}
            fn progress(&mut self, _: bool) -> &mut dyn ProgressSink {
                &mut self.0
            }
        }
        for preset in Preset::ALL {
            let out = std::env::temp_dir().join(format!(
                "metamer-hands-{}-{}",
                preset.name(),
                std::process::id()
            ));
            let _ = std::fs::remove_dir_all(&out);
            let request = Request {
                out: out.clone(),
                screen: ScreenSpec::Virtual(preset),
                virtual_white_cd_m2: None,
                instrument: "sim:i1pro?time_scale=0".into(),
                speed: None,
                plan: PlanOptions {
                    ramp_steps: 3,
                    repeats: 1,
                    grid_steps: 0,
                },
                adaptive: None,
                model: ModelKind::Plcc,
                settle: Some(std::time::Duration::ZERO),
                resume: false,
                force: false,
                attend: Attend::Terminal { unattended: true },
                simulated_meter: SimulatedMeter::Warn,
                run: RunOptions::default(),
            };
            let outcome = characterize(&request, &mut Quiet(NoProgress))
                .unwrap_or_else(|e| panic!("{}: {e}", preset.name()));
            let Outcome::Finished(summary) = outcome else {
                panic!("{}: nothing stops a simulated session", preset.name())
            };
            let want = preset.params().black_cd_m2;
            let got = summary.black_xyz.y;
            assert!(
                (got - want).abs() < 5.0 * 0.013,
                "{}: black Y {got}, the preset's {want}",
                preset.name()
            );
            std::fs::remove_dir_all(&out).unwrap();
        }
    }
}
