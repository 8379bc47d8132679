//! Undo and redo (Ctrl+Z, Ctrl+Shift+Z or Ctrl+Y) of what the user does to the 3D view: the transfer function
//! (its points, colour map and value window), the clipping plane and the camera.
//!
//! The history is of whole gestures, not of frames: it is told the edited state once a frame
//! ([`History::observe`]) and whether a gesture is still under way (a button held, a fly-to, a wheel still
//! turning). A change becomes one step when the state settles, so a whole drag of a point, of the plane or of the
//! camera is undone at once. A new edit after an undo drops what could have been redone, as every editor does.

use super::orbit::OrbitView;
use super::Model;
use crate::scene::clip::ClipPlane;
use crate::transfer::colormap::Colormap;
use crate::transfer::function::TransferFunction;
use std::collections::VecDeque;

/// How many steps back the history reaches: a long session forgets its oldest steps.
pub const DEPTH: usize = 100;

/// The undoable state: what a step restores.
#[derive(Clone, Debug, PartialEq)]
pub struct Snapshot {
    pub transfer_function: Option<TransferFunction>,
    pub colormap: Colormap,
    pub window: [f32; 2],
    pub clip_plane: Option<ClipPlane>,
    pub orbit: OrbitView,
}

impl Snapshot {
    pub fn of(model: &Model) -> Snapshot {
        Snapshot {
            transfer_function: model.look.colour.transfer_function.clone(),
            colormap: model.look.colour.colormap,
            window: model.look.colour.window,
            clip_plane: model.look.cut.clip_plane,
            orbit: model.camera.orbit,
        }
    }

    /// Puts this state back into `model`, stopping any fly-to (it would carry the camera off again).
    pub fn restore(self, model: &mut Model) {
        model.look.colour.transfer_function = self.transfer_function;
        model.look.colour.colormap = self.colormap;
        model.look.colour.window = self.window;
        model.look.cut.clip_plane = self.clip_plane;
        model.camera.orbit = self.orbit;
        model.camera.animation = None;
    }
}

impl Model {
    /// Records the state as it stands after a frame; `busy`: a gesture is under way (see [`History::observe`]).
    pub fn observe_history(&mut self, busy: bool) {
        let now = Snapshot::of(self);
        self.history.observe(&self.volume.label, now, busy);
    }

    /// Ctrl+Z: back one step; false when there was none.
    pub fn undo(&mut self) -> bool {
        let now = Snapshot::of(self);
        self.history.undo(now).map(|s| s.restore(self)).is_some()
    }

    /// Ctrl+Shift+Z or Ctrl+Y: forward one step; false when there was none.
    pub fn redo(&mut self) -> bool {
        let now = Snapshot::of(self);
        self.history.redo(now).map(|s| s.restore(self)).is_some()
    }
}

/// The steps that can be undone and redone, and the state they lead from.
#[derive(Clone, Debug, Default)]
pub struct History {
    undo: VecDeque<Snapshot>,
    redo: Vec<Snapshot>,
    /// The state after the last finished gesture (`None` before the first observation).
    settled: Option<Snapshot>,
    /// The volume the steps are of: another one's camera and Hounsfield-unit points mean nothing here.
    volume: String,
}

impl History {
    /// Once a frame: the edited state `now` of the volume labelled `volume`, and whether a gesture is under way
    /// (then nothing is recorded: the gesture becomes one step when it ends).
    pub fn observe(&mut self, volume: &str, now: Snapshot, busy: bool) {
        if self.volume != volume {
            *self = History {
                volume: volume.to_string(),
                ..History::default()
            };
        }
        if !busy {
            self.commit(now);
        }
    }

    /// The state before the last step, to show instead of `now` (`None`: nothing to undo). An edit not yet
    /// recorded (`now` differs from the settled state) is a step of its own, and it is that one undone.
    pub fn undo(&mut self, now: Snapshot) -> Option<Snapshot> {
        self.commit(now);
        let before = self.undo.pop_back()?;
        let current = self.settled.replace(before.clone())?;
        self.redo.push(current);
        Some(before)
    }

    /// The state the last undo left, to show instead of `now` (`None`: nothing to redo, or an edit since).
    pub fn redo(&mut self, now: Snapshot) -> Option<Snapshot> {
        self.commit(now);
        let after = self.redo.pop()?;
        if let Some(current) = self.settled.replace(after.clone()) {
            self.undo.push_back(current);
        }
        Some(after)
    }

    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }

    /// `now` is settled: if it differs from the last settled state, that state becomes a step back and the redo
    /// steps are dropped.
    fn commit(&mut self, now: Snapshot) {
        match &self.settled {
            Some(settled) if *settled == now => {}
            Some(_) => {
                let before = self.settled.replace(now).expect("matched Some");
                self.undo.push_back(before);
                if self.undo.len() > DEPTH {
                    self.undo.pop_front();
                }
                self.redo.clear();
            }
            None => self.settled = Some(now),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn state(window_lo: f32) -> Snapshot {
        let model = Model::new(Vec3::ONE, "x".into());
        let mut s = Snapshot::of(&model);
        s.window[0] = window_lo;
        s
    }

    #[test]
    fn a_gesture_is_one_step_however_many_frames_it_lasts() {
        let mut h = History::default();
        h.observe("v", state(0.0), false);
        for k in 1..=30 {
            h.observe("v", state(k as f32 / 100.0), true);
        }
        h.observe("v", state(0.3), false);
        assert_eq!(h.undo(state(0.3)), Some(state(0.0)), "the whole drag undone at once");
        assert!(!h.can_undo());
        assert_eq!(h.redo(state(0.0)), Some(state(0.3)));
        assert!(!h.can_redo());
    }

    #[test]
    fn undo_and_redo_walk_the_steps_and_a_new_edit_drops_the_redo_tail() {
        let mut h = History::default();
        for k in 0..4 {
            h.observe("v", state(k as f32), false);
        }
        assert_eq!(h.undo(state(3.0)), Some(state(2.0)));
        assert_eq!(h.undo(state(2.0)), Some(state(1.0)));
        assert_eq!(h.redo(state(1.0)), Some(state(2.0)));
        // A new edit from 2: 3 can no longer be redone.
        h.observe("v", state(9.0), false);
        assert!(!h.can_redo());
        assert_eq!(h.redo(state(9.0)), None);
        assert_eq!(h.undo(state(9.0)), Some(state(2.0)));
        assert_eq!(h.undo(state(2.0)), Some(state(1.0)));
        assert_eq!(h.undo(state(1.0)), Some(state(0.0)));
        assert_eq!(h.undo(state(0.0)), None, "nothing before the first state");
    }

    #[test]
    fn an_edit_not_yet_observed_is_undone_first() {
        // A key edit (C: clip plane on) and Ctrl+Z in the same frame: the edit is the step undone.
        let mut h = History::default();
        h.observe("v", state(0.0), false);
        assert_eq!(h.undo(state(5.0)), Some(state(0.0)));
        assert_eq!(h.redo(state(0.0)), Some(state(5.0)));
        // And a pending edit when redo is asked for is a new edit: nothing to redo.
        assert_eq!(h.undo(state(5.0)), Some(state(0.0)));
        assert_eq!(h.redo(state(7.0)), None);
        assert_eq!(h.undo(state(7.0)), Some(state(0.0)));
    }

    #[test]
    fn the_history_is_bounded_and_belongs_to_one_volume() {
        let mut h = History::default();
        for k in 0..=DEPTH + 20 {
            h.observe("v", state(k as f32), false);
        }
        let mut now = state((DEPTH + 20) as f32);
        let mut steps = 0;
        while let Some(before) = h.undo(now.clone()) {
            now = before;
            steps += 1;
        }
        assert_eq!(steps, DEPTH);
        assert_eq!(now, state(20.0), "the oldest steps are forgotten");
        h.observe("other", state(1.0), false);
        assert!(!h.can_undo() && !h.can_redo(), "another volume starts afresh");
    }

    #[test]
    fn a_snapshot_restores_the_transfer_function_plane_and_camera() {
        let mut model = Model::new(Vec3::ONE, "x".into());
        let before = Snapshot::of(&model);
        model.look.colour.transfer_function = TransferFunction::preset("ct-bone").ok();
        model.look.cut.clip_plane = ClipPlane::through(Vec3::X, Vec3::ZERO).ok();
        model.camera.orbit.turn(0.5);
        model.look.colour.window = [0.2, 0.8];
        assert_ne!(Snapshot::of(&model), before);
        before.clone().restore(&mut model);
        assert_eq!(Snapshot::of(&model), before);
    }

    /// What the user sees of each recorded setting, read from the model itself (not a snapshot, which could drop a
    /// field both ways): the transfer function, colour map, value window, clipping plane and camera.
    fn shown(
        m: &Model,
    ) -> (
        Option<TransferFunction>,
        Colormap,
        [f32; 2],
        Option<ClipPlane>,
        OrbitView,
    ) {
        let c = &m.look.colour;
        (
            c.transfer_function.clone(),
            c.colormap,
            c.window,
            m.look.cut.clip_plane,
            m.camera.orbit,
        )
    }

    #[test]
    fn undo_and_redo_restore_each_recorded_setting_on_its_own() {
        type Edit = fn(&mut Model);
        let edits: [(&str, Edit); 5] = [
            ("transfer function", |m| {
                m.look.colour.transfer_function = TransferFunction::preset("ct-bone").ok()
            }),
            ("colour map", |m| m.look.colour.colormap = Colormap::Viridis),
            ("value window", |m| m.look.colour.window = [0.3, 0.7]),
            ("clipping plane", |m| {
                m.look.cut.clip_plane = ClipPlane::through(Vec3::Y, Vec3::ZERO).ok()
            }),
            ("camera", |m| m.camera.orbit.turn(0.7)),
        ];
        for (name, edit) in edits {
            let mut model = Model::new(Vec3::ONE, "x".into());
            model.observe_history(false);
            let before = shown(&model);
            edit(&mut model);
            let after = shown(&model);
            assert_ne!(after, before, "{name}: the edit changes what is shown");
            model.observe_history(false);
            assert!(model.undo(), "{name}: the edit is a step");
            assert_eq!(shown(&model), before, "{name}: undo restores it");
            assert!(model.redo(), "{name}: and it can be redone");
            assert_eq!(shown(&model), after, "{name}: redo restores the edit");
        }
    }
}
