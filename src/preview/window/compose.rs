//! Composing a shot in the interactive preview (`chambre preview --window`): keys and the
//! mouse move the film and turn the camera ([`Composer`]), by steps of a degree and a
//! millimetre, the film's tilt and swing kept short of a right angle; the composition is saved
//! as the camera's overrides, which the ray tracer renders.

use glam::{DQuat, DVec3};

use crate::camera::{CameraSpec, Projection};

/// A key of the interactive preview (`chambre preview --window`), from the keyboard or from a
/// `--keys` script.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ComposeKey {
    /// Arrow up: film tilt up by `TURN_STEP_DEG`.
    Up,
    /// Arrow down: film tilt down.
    Down,
    /// Arrow left: film swing left.
    Left,
    /// Arrow right: film swing right.
    Right,
    /// A character key (see [`Composer::apply`]).
    Char(char),
    /// Escape: quit.
    Escape,
}

impl ComposeKey {
    /// A key named in a `--keys` script: `up`, `down`, `left`, `right`, `escape`, or one
    /// character.
    pub fn parse(name: &str) -> Option<ComposeKey> {
        Some(match name {
            "up" => ComposeKey::Up,
            "down" => ComposeKey::Down,
            "left" => ComposeKey::Left,
            "right" => ComposeKey::Right,
            "escape" | "esc" => ComposeKey::Escape,
            _ => {
                let mut chars = name.chars();
                match (chars.next(), chars.next()) {
                    (Some(c), None) => ComposeKey::Char(c.to_ascii_lowercase()),
                    _ => return None,
                }
            }
        })
    }
}

/// What a key asks of the window.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ComposeAction {
    /// The camera changed: draw again.
    Changed,
    /// Save the composed scene.
    Save,
    /// Close the window.
    Quit,
    /// Nothing (a key without a meaning).
    Nothing,
}

/// Degrees a tilt, swing, pan or pitch key turns.
pub const TURN_STEP_DEG: f64 = 1.0;
/// Millimetres a shift key, or a notch of the mouse wheel, moves the film (an orthographic
/// camera's window: the same fraction of its height as of a 24 mm film's).
pub const SHIFT_STEP_MM: f64 = 1.0;
/// Degrees a mouse drag turns the camera or the film for each pixel the mouse moves: a drag
/// across a 320-pixel preview turns 32°.
pub const DRAG_DEG_PER_PX: f64 = 0.1;
/// Film tilt and swing, and the camera's pitch, stay within ± this (degrees): the scene
/// format's (−90°, 90°).
const TURN_LIMIT_DEG: f64 = 89.0;

/// What a drag of the mouse in the interactive preview moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Drag {
    /// The left button: the camera pans and pitches after the mouse (right and up).
    Camera,
    /// The right button: the film swings and tilts after the mouse (right and up), as the
    /// arrow keys move it.
    Film,
}

/// The camera a user composes in the interactive preview: the scene's camera with film tilt,
/// swing and shift, and the camera turned (panned and pitched about its position). Keys:
/// arrows tilt and swing the film, `i`/`k` shift it up/down, `j`/`l` left/right, `a`/`d` pan
/// the camera, `w`/`x` pitch it, `r` resets, `s` saves, `q` or Escape quits. The mouse: a drag
/// with the left button turns the camera, with the right button the film (`Drag`), and the
/// wheel shifts the film.
#[derive(Clone, Debug)]
pub struct Composer {
    base: CameraSpec,
    /// Film tilt, swing (degrees) and shift (mm), as the scene fields are.
    pub film_tilt: f64,
    /// Film swing (degrees).
    pub film_swing: f64,
    /// Film shift [right, up] (mm).
    pub film_shift: [f64; 2],
    /// The camera turned right about its up direction (degrees).
    pub pan: f64,
    /// The camera turned up about its right direction (degrees).
    pub pitch: f64,
}

impl Composer {
    /// Starts from `camera` as the scene has it.
    pub fn new(camera: &CameraSpec) -> Composer {
        let m = &camera.movements;
        Composer {
            base: camera.clone(),
            film_tilt: m.film_tilt,
            film_swing: m.film_swing,
            film_shift: m.film_shift,
            pan: 0.0,
            pitch: 0.0,
        }
    }

    /// Applies one key; film tilt and swing stay inside the scene format's (−90°, 90°).
    pub fn apply(&mut self, key: ComposeKey) -> ComposeAction {
        let turn = |v: &mut f64, d: f64| *v = turned(*v, d);
        let step = self.shift_step_mm();
        match key {
            ComposeKey::Up => turn(&mut self.film_tilt, TURN_STEP_DEG),
            ComposeKey::Down => turn(&mut self.film_tilt, -TURN_STEP_DEG),
            ComposeKey::Left => turn(&mut self.film_swing, -TURN_STEP_DEG),
            ComposeKey::Right => turn(&mut self.film_swing, TURN_STEP_DEG),
            ComposeKey::Char('i') => self.film_shift[1] += step,
            ComposeKey::Char('k') => self.film_shift[1] -= step,
            ComposeKey::Char('j') => self.film_shift[0] -= step,
            ComposeKey::Char('l') => self.film_shift[0] += step,
            ComposeKey::Char('a') => self.pan -= TURN_STEP_DEG,
            ComposeKey::Char('d') => self.pan += TURN_STEP_DEG,
            ComposeKey::Char('w') => turn(&mut self.pitch, TURN_STEP_DEG),
            ComposeKey::Char('x') => turn(&mut self.pitch, -TURN_STEP_DEG),
            ComposeKey::Char('r') => *self = Composer::new(&self.base),
            ComposeKey::Char('s') => return ComposeAction::Save,
            ComposeKey::Char('q') | ComposeKey::Escape => return ComposeAction::Quit,
            ComposeKey::Char(_) => return ComposeAction::Nothing,
        }
        ComposeAction::Changed
    }

    /// Applies a drag of the mouse by `dx` pixels right and `dy` down (the window's cursor
    /// coordinates): what `drag` moves follows it, `DRAG_DEG_PER_PX` a pixel.
    pub fn drag(&mut self, drag: Drag, dx: f64, dy: f64) -> ComposeAction {
        if dx == 0.0 && dy == 0.0 {
            return ComposeAction::Nothing;
        }
        let (right, up) = (dx * DRAG_DEG_PER_PX, -dy * DRAG_DEG_PER_PX);
        match drag {
            Drag::Camera => {
                self.pan += right;
                self.pitch = turned(self.pitch, up);
            }
            Drag::Film => {
                self.film_swing = turned(self.film_swing, right);
                self.film_tilt = turned(self.film_tilt, up);
            }
        }
        ComposeAction::Changed
    }

    /// Applies a turn of the mouse wheel by `notches` (away from the user positive) and
    /// `across` (right positive, a wheel that tilts or a touchpad): the film shifts up and
    /// right, `SHIFT_STEP_MM` a notch.
    pub fn wheel(&mut self, across: f64, notches: f64) -> ComposeAction {
        if across == 0.0 && notches == 0.0 {
            return ComposeAction::Nothing;
        }
        let step = self.shift_step_mm();
        self.film_shift[0] += across * step;
        self.film_shift[1] += notches * step;
        ComposeAction::Changed
    }

    /// The point the turned camera looks at: the scene's `look_at` rotated about the camera's
    /// position, by `pan` about the scene's up and `pitch` about the camera's right.
    pub fn look_at(&self) -> DVec3 {
        let c = &self.base;
        let view = c.look_at - c.position;
        let up = c.up.normalize();
        let panned = DQuat::from_axis_angle(up, -self.pan.to_radians()) * view;
        let right = panned.cross(up).normalize();
        let pitched = DQuat::from_axis_angle(right, self.pitch.to_radians()) * panned;
        c.position + pitched
    }

    /// The scene's camera as composed. A focus solved from `focus_points` is kept as it was
    /// (the preview draws a pinhole; the saved scene solves it again).
    pub fn camera(&self) -> CameraSpec {
        let mut camera = self.base.clone();
        camera.look_at = self.look_at();
        camera.movements.film_tilt = self.film_tilt;
        camera.movements.film_swing = self.film_swing;
        camera.movements.film_shift = self.film_shift;
        camera
    }

    /// How far a shift key moves the film (mm): `SHIFT_STEP_MM`, or for an orthographic
    /// camera the same fraction of its window's height as of a 24 mm film.
    fn shift_step_mm(&self) -> f64 {
        match self.base.projection {
            Projection::Perspective => SHIFT_STEP_MM,
            Projection::Orthographic => SHIFT_STEP_MM * self.base.film_mm[1] / 24.0,
        }
    }

    /// The film shift in the scene file's units, and their name: mm, or scene units for an
    /// orthographic camera's window.
    fn shift_as_given(&self) -> ([f64; 2], &'static str) {
        match self.base.projection {
            Projection::Perspective => (self.film_shift, "mm"),
            Projection::Orthographic => (
                self.film_shift.map(|v| v * self.base.units_per_mm),
                "scene units",
            ),
        }
    }

    /// The scene overrides (`--set` syntax) that give a scene this composition.
    pub fn overrides(&self) -> Vec<String> {
        // `{:?}` writes 1.0 as `1.0`, which TOML reads as a float, as the fields are.
        let [x, y, z] = self.look_at().to_array();
        let (shift, _) = self.shift_as_given();
        vec![
            format!("camera.film_tilt={:?}", self.film_tilt),
            format!("camera.film_swing={:?}", self.film_swing),
            format!("camera.film_shift=[{:?}, {:?}]", shift[0], shift[1]),
            format!("camera.look_at=[{x:?}, {y:?}, {z:?}]"),
        ]
    }

    /// The movements and turns, for the window's title and the terminal.
    pub fn figures(&self) -> String {
        let (shift, unit) = self.shift_as_given();
        format!(
            "film tilt {:+.1}°, swing {:+.1}°, shift [{:+.1}, {:+.1}] {unit}; camera pan \
             {:+.1}°, pitch {:+.1}°",
            self.film_tilt, self.film_swing, shift[0], shift[1], self.pan, self.pitch
        )
    }
}

/// `v` turned by `d` degrees, kept within `TURN_LIMIT_DEG`.
fn turned(v: f64, d: f64) -> f64 {
    (v + d).clamp(-TURN_LIMIT_DEG, TURN_LIMIT_DEG)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;
    use std::path::Path;

    fn camera() -> CameraSpec {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/architecture.toml");
        Scene::load(&path, &[]).unwrap().camera
    }

    #[test]
    fn keys_move_the_film_and_turn_the_camera_by_their_steps() {
        let start = camera();
        let mut composer = Composer::new(&start);
        for key in ["up", "up", "left", "i", "l", "l", "d", "w"] {
            let key = ComposeKey::parse(key).unwrap();
            assert_eq!(composer.apply(key), ComposeAction::Changed);
        }
        let m = &start.movements;
        assert_eq!(composer.film_tilt, m.film_tilt + 2.0);
        assert_eq!(composer.film_swing, m.film_swing - 1.0);
        assert_eq!(
            composer.film_shift,
            [m.film_shift[0] + 2.0, m.film_shift[1] + 1.0]
        );
        // Turning keeps the distance to the point looked at, and turns by the angle asked.
        let before = start.look_at - start.position;
        let after = composer.look_at() - start.position;
        assert!((after.length() - before.length()).abs() < 1e-9 * before.length());
        let angle = before.angle_between(after).to_degrees();
        assert!(angle > 1.0 && angle < 2.0, "{angle}");
        assert_eq!(composer.apply(ComposeKey::Char('s')), ComposeAction::Save);
        assert_eq!(composer.apply(ComposeKey::Escape), ComposeAction::Quit);
        assert_eq!(
            composer.apply(ComposeKey::Char('z')),
            ComposeAction::Nothing
        );
        composer.apply(ComposeKey::Char('r'));
        assert_eq!(composer.film_tilt, m.film_tilt);
        assert!((composer.look_at() - start.look_at).length() < 1e-12);
    }

    #[test]
    fn the_mouse_turns_what_it_drags_after_it_and_its_wheel_shifts_the_film() {
        let start = camera();
        let m = &start.movements;
        let mut composer = Composer::new(&start);
        // 50 px right and 20 px up with the left button: the camera pans right 5° and pitches
        // up 2°; the film stays.
        assert_eq!(
            composer.drag(Drag::Camera, 50.0, -20.0),
            ComposeAction::Changed
        );
        assert_eq!((composer.pan, composer.pitch), (5.0, 2.0));
        assert_eq!(
            (composer.film_tilt, composer.film_swing),
            (m.film_tilt, m.film_swing)
        );
        let mut keyed = Composer::new(&start);
        for _ in 0..5 {
            keyed.apply(ComposeKey::Char('d'));
        }
        for _ in 0..2 {
            keyed.apply(ComposeKey::Char('w'));
        }
        let (dragged, typed) = (composer.look_at(), keyed.look_at());
        assert!((dragged - typed).length() < 1e-12, "{dragged} {typed}");
        // The right button moves the film as the arrow keys do: 30 px left and 10 px down.
        composer.drag(Drag::Film, -30.0, 10.0);
        assert_eq!(composer.film_swing, m.film_swing - 3.0);
        assert_eq!(composer.film_tilt, m.film_tilt - 1.0);
        // Two notches away from the user and one to the right.
        assert_eq!(composer.wheel(1.0, 2.0), ComposeAction::Changed);
        assert_eq!(
            composer.film_shift,
            [m.film_shift[0] + 1.0, m.film_shift[1] + 2.0]
        );
        // A move that moves nothing asks for no frame; a drag's tilt stops as a key's does.
        assert_eq!(composer.drag(Drag::Film, 0.0, 0.0), ComposeAction::Nothing);
        assert_eq!(composer.wheel(0.0, 0.0), ComposeAction::Nothing);
        composer.drag(Drag::Film, 0.0, -1e6);
        assert_eq!(composer.film_tilt, TURN_LIMIT_DEG);
        composer.drag(Drag::Camera, 0.0, 1e6);
        assert_eq!(composer.pitch, -TURN_LIMIT_DEG);
    }

    #[test]
    fn film_tilt_stops_short_of_a_right_angle() {
        let mut composer = Composer::new(&camera());
        for _ in 0..200 {
            composer.apply(ComposeKey::Up);
        }
        assert_eq!(composer.film_tilt, 89.0);
    }

    #[test]
    fn the_overrides_give_the_composed_camera() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/architecture.toml");
        let mut composer = Composer::new(&camera());
        for key in ["down", "down", "right", "k", "a", "x"] {
            composer.apply(ComposeKey::parse(key).unwrap());
        }
        let reloaded = Scene::load(&path, &composer.overrides()).unwrap().camera;
        let composed = composer.camera();
        assert_eq!(reloaded.movements, composed.movements);
        assert!((reloaded.look_at - composed.look_at).length() < 1e-9);
    }

    #[test]
    fn an_orthographic_composition_saves_its_shift_in_scene_units() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/elevation.toml");
        let camera = Scene::load(&path, &[]).unwrap().camera;
        let mut composer = Composer::new(&camera);
        for key in ["i", "i", "l", "up"] {
            composer.apply(ComposeKey::parse(key).unwrap());
        }
        // A step is 1/24 of the 48-unit window's height: 2 units.
        let [x, y] = camera.movements.film_shift.map(|v| v * camera.units_per_mm);
        assert!(composer.figures().contains(&format!(
            "shift [{:+.1}, {:+.1}] scene units",
            x + 2.0,
            y + 4.0
        )));
        let reloaded = Scene::load(&path, &composer.overrides()).unwrap().camera;
        let composed = composer.camera();
        for (a, b) in reloaded
            .movements
            .film_shift
            .iter()
            .zip(composed.movements.film_shift)
        {
            assert!((a - b).abs() < 1e-9 * b.abs().max(1.0), "{a} against {b}");
        }
        assert_eq!(reloaded.movements.film_tilt, composed.movements.film_tilt);
    }
}
