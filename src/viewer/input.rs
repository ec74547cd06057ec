//! The viewer's input: window events, keys and mouse, and the camera and
//! lights they move each frame.

use super::{App, Overlay, PathMotion};
use crate::measure::flicker::path_camera;
use crate::scene::orbit;
use glam::Vec2;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::ActiveEventLoop;
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::WindowId;

impl App {
    /// Moves the camera one frame of `dt` seconds along its path or by the
    /// keys held, and the selected light by the arrow keys.
    pub(super) fn update_camera(&mut self, dt: f32) {
        let Some(s) = &mut self.scene else { return };
        // The path selector: (re)start from the current camera, or stop.
        let motion = &mut self.state.camera_motion;
        if motion.map(|m| m.path) != self.state.camera_path {
            *motion = self.state.camera_path.map(|path| PathMotion {
                path,
                start: s.camera,
                frame: 0,
            });
        }
        if let Some(m) = motion {
            m.frame += 1;
            s.camera = path_camera(&m.start, m.path, m.frame);
        }
        let speed = (s.camera.eye - s.camera.target).length().max(1.0) * dt;
        let k = |c: KeyCode| self.keys.contains(&c) as i32 as f32;
        let (f, r, u) = (
            k(KeyCode::KeyW) - k(KeyCode::KeyS),
            k(KeyCode::KeyD) - k(KeyCode::KeyA),
            k(KeyCode::KeyE) - k(KeyCode::KeyQ),
        );
        if f != 0.0 || r != 0.0 || u != 0.0 {
            orbit::fly(&mut s.camera, f * speed, r * speed, u * speed);
        }
        // Arrow keys and PageUp/PageDown move the selected light.
        let (lx, lz, ly) = (
            k(KeyCode::ArrowRight) - k(KeyCode::ArrowLeft),
            k(KeyCode::ArrowDown) - k(KeyCode::ArrowUp),
            k(KeyCode::PageUp) - k(KeyCode::PageDown),
        );
        if let Some(l) = s.lights.get_mut(self.state.selected_light)
            && (lx != 0.0 || ly != 0.0 || lz != 0.0)
        {
            l.position += glam::Vec3::new(lx, ly, lz) * speed * 0.5;
        }
    }
}

/// What a key does in the viewer rather than in the panels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Shortcut {
    Screenshot,
    Help,
    Panel,
    MaskView,
    Heatmap,
    /// Selects light `n` (lights count from 0, as everywhere).
    Light(usize),
    /// Closes the dock, or quits when none is open.
    Escape,
    /// A movement key, acting while it is held.
    Held,
}

impl Shortcut {
    fn of(code: KeyCode) -> Option<Shortcut> {
        use KeyCode::*;
        Some(match code {
            F12 | KeyP => Shortcut::Screenshot,
            F1 => Shortcut::Help,
            Tab => Shortcut::Panel,
            KeyM => Shortcut::MaskView,
            KeyH => Shortcut::Heatmap,
            Digit0 => Shortcut::Light(0),
            Digit1 => Shortcut::Light(1),
            Digit2 => Shortcut::Light(2),
            Digit3 => Shortcut::Light(3),
            Escape => Shortcut::Escape,
            KeyW | KeyA | KeyS | KeyD | KeyQ | KeyE | ArrowLeft | ArrowRight | ArrowUp
            | ArrowDown | PageUp | PageDown => Shortcut::Held,
            _ => return None,
        })
    }

    /// The shortcut a key press is, unless a text field has the keyboard:
    /// a focused checkbox or slider does not take Tab, Esc or the movement
    /// keys from the view (egui reports any focused widget as wanting the
    /// keyboard, and takes Tab for focus navigation).
    fn routed(ctx: &egui::Context, code: KeyCode) -> Option<Shortcut> {
        if ctx.text_edit_focused() {
            None
        } else {
            Shortcut::of(code)
        }
    }
}

/// The view's size in physical pixels (the window right of the panel).
fn view_size(window: &winit::window::Window, view_left: u32) -> Vec2 {
    let size = window.inner_size();
    Vec2::new(
        size.width.saturating_sub(view_left).max(1) as f32,
        size.height.max(1) as f32,
    )
}

/// Whether a press at `pointer` (physical pixels in the window) starts a
/// camera or light drag: only inside the 3D view, neither on the side panel
/// (left of `view_left`) nor on the dock, and not when egui took the press.
fn starts_view_drag(
    egui_took_it: bool,
    pointer: Vec2,
    view_left: u32,
    dock: Option<egui::Rect>,
) -> bool {
    !egui_took_it
        && pointer.x >= view_left as f32
        && !dock.is_some_and(|r| r.contains(egui::pos2(pointer.x, pointer.y)))
}

impl App {
    /// Acts on a viewer shortcut pressed (or, for a held key, released).
    fn on_shortcut(
        &mut self,
        code: KeyCode,
        shortcut: Shortcut,
        pressed: bool,
        repeat: bool,
        event_loop: &ActiveEventLoop,
    ) {
        if !pressed {
            self.keys.remove(&code);
            return;
        }
        self.keys.insert(code);
        if repeat {
            return;
        }
        let state = &mut self.state;
        match shortcut {
            Shortcut::Screenshot => state.screenshot_requested = true,
            Shortcut::Help => state.show_help = !state.show_help,
            Shortcut::Panel => state.show_panel = !state.show_panel,
            Shortcut::MaskView => {
                state.overlay = match state.overlay {
                    Overlay::Image => Overlay::Mask(state.selected_light),
                    Overlay::Mask(_) => Overlay::Image,
                }
            }
            Shortcut::Heatmap => self.start_heatmap(),
            Shortcut::Light(i) => {
                if self.scene.as_ref().is_some_and(|s| i < s.lights.len()) {
                    state.selected_light = i;
                }
            }
            Shortcut::Escape if state.dock_open() => state.close_dock(),
            Shortcut::Escape => event_loop.exit(),
            Shortcut::Held => {}
        }
    }

    /// Moves the camera, or the light being dragged, with the pointer.
    fn on_pointer_moved(&mut self, pointer: Vec2, sz: Vec2) {
        let d = pointer - self.pointer;
        self.pointer = pointer;
        // The pointer relative to the 3D view (right of the panel).
        let p = pointer - Vec2::new(self.state.view_left as f32, 0.0);
        let Some(s) = &mut self.scene else { return };
        if let Some(li) = self.dragging_light {
            let vp = s.camera.projection(sz.x / sz.y) * s.camera.view();
            if let Some(l) = s.lights.get_mut(li)
                && let Some(q) = orbit::drag_point(&s.camera, vp, sz, p, l.position)
            {
                l.position = q;
            }
        } else if self.buttons[0] {
            orbit::orbit(&mut s.camera, d.x / sz.y * 3.0, d.y / sz.y * 3.0);
        } else if self.buttons[2] {
            orbit::pan(&mut s.camera, d.x / sz.y, d.y / sz.y);
        } else if self.buttons[1] {
            orbit::zoom(&mut s.camera, (1.0 + d.y / sz.y * 2.0).max(0.1));
        }
    }

    /// Starts or ends a drag; a left press on a light's icon (within 16 px)
    /// grabs that light.
    fn on_button(&mut self, button: usize, pressed: bool, egui_took_it: bool, sz: Vec2) {
        if !pressed {
            self.buttons[button] = false;
            self.dragging_light = None;
            return;
        }
        if !starts_view_drag(
            egui_took_it,
            self.pointer,
            self.state.view_left,
            self.state.dock_rect,
        ) {
            return;
        }
        self.buttons[button] = true;
        let Some(s) = &self.scene else { return };
        if button == 0 {
            let p = self.pointer - Vec2::new(self.state.view_left as f32, 0.0);
            let vp = s.camera.projection(sz.x / sz.y) * s.camera.view();
            self.dragging_light = s.lights.iter().position(|l| {
                l.kind != crate::scene::LightType::Directional
                    && orbit::project(vp, sz, l.position).is_some_and(|q| q.distance(p) < 16.0)
            });
            if let Some(li) = self.dragging_light {
                self.state.selected_light = li;
            }
        }
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gfx.is_none()
            && let Err(e) = self.init(event_loop)
        {
            self.exit_error = Some(e);
            event_loop.exit();
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(gfx) = &mut self.gfx else { return };
        // Shortcuts go to the view and not to egui (which would move its
        // focus on Tab), unless a text field is being edited.
        if let WindowEvent::KeyboardInput { event: key, .. } = &event
            && let PhysicalKey::Code(code) = key.physical_key
            && let Some(shortcut) = Shortcut::routed(&gfx.egui_ctx, code)
        {
            let pressed = key.state == ElementState::Pressed;
            if pressed {
                gfx.egui_ctx.memory_mut(|m| {
                    if let Some(id) = m.focused() {
                        m.surrender_focus(id)
                    }
                });
            }
            self.on_shortcut(code, shortcut, pressed, key.repeat, event_loop);
            return;
        }
        let consumed = gfx.egui_state.on_window_event(&gfx.window, &event).consumed;
        let sz = view_size(&gfx.window, self.state.view_left);
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw(event_loop) {
                    self.exit_error = Some(e);
                    event_loop.exit();
                }
            }
            // A key released while a text field had the keyboard.
            WindowEvent::KeyboardInput { event, .. } => {
                if let PhysicalKey::Code(code) = event.physical_key
                    && event.state == ElementState::Released
                {
                    self.keys.remove(&code);
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                self.on_pointer_moved(Vec2::new(position.x as f32, position.y as f32), sz)
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let i = match button {
                    MouseButton::Left => 0,
                    MouseButton::Middle => 1,
                    MouseButton::Right => 2,
                    _ => return,
                };
                self.on_button(i, state == ElementState::Pressed, consumed, sz);
            }
            WindowEvent::MouseWheel { delta, .. }
                if starts_view_drag(
                    consumed,
                    self.pointer,
                    self.state.view_left,
                    self.state.dock_rect,
                ) =>
            {
                let y = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                if let Some(s) = &mut self.scene {
                    orbit::zoom(&mut s.camera, 0.9f32.powf(y));
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(gfx) = &self.gfx {
            gfx.window.request_redraw();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A press on the side panel, on the dock or taken by egui never moves
    /// the camera; one in the open view does.
    #[test]
    fn drags_start_only_in_the_view() {
        let dock = Some(egui::Rect::from_min_max(
            egui::pos2(900.0, 8.0),
            egui::pos2(1272.0, 400.0),
        ));
        let at = |x: f32, y: f32| Vec2::new(x, y);
        assert!(starts_view_drag(false, at(500.0, 300.0), 320, dock));
        assert!(!starts_view_drag(true, at(500.0, 300.0), 320, dock));
        assert!(!starts_view_drag(false, at(310.0, 300.0), 320, dock));
        assert!(!starts_view_drag(false, at(1000.0, 200.0), 320, dock));
        assert!(starts_view_drag(false, at(1000.0, 600.0), 320, dock));
        assert!(starts_view_drag(false, at(10.0, 10.0), 0, None));
    }

    /// Tab, Esc and the movement keys reach the view while a checkbox has
    /// the focus (egui would take Tab to move its focus), and go to egui
    /// while a text field is edited.
    #[test]
    fn shortcuts_reach_the_view_unless_text_is_edited() {
        let ctx = egui::Context::default();
        let (mut checked, mut text) = (false, String::new());
        // One frame of a checkbox and a text field; `focus` 0 or 1 gives
        // the one at that index the focus.
        let mut frame = |focus: Option<usize>| {
            ctx.run_ui(Default::default(), |ui| {
                let ids = [
                    ui.checkbox(&mut checked, "c").id,
                    ui.text_edit_singleline(&mut text).id,
                ];
                if let Some(i) = focus {
                    ui.memory_mut(|m| m.request_focus(ids[i]));
                }
            })
            .drop_without_applying_deltas();
        };
        frame(None);
        frame(Some(0));
        frame(None);
        assert!(
            ctx.egui_wants_keyboard_input(),
            "the checkbox has the focus"
        );
        for (code, want) in [
            (KeyCode::Tab, Shortcut::Panel),
            (KeyCode::Escape, Shortcut::Escape),
            (KeyCode::KeyW, Shortcut::Held),
            (KeyCode::Digit0, Shortcut::Light(0)),
        ] {
            assert_eq!(Shortcut::routed(&ctx, code), Some(want));
        }
        frame(Some(1));
        frame(None);
        assert!(ctx.text_edit_focused());
        assert_eq!(Shortcut::routed(&ctx, KeyCode::Tab), None);
        assert_eq!(Shortcut::routed(&ctx, KeyCode::KeyW), None);
        assert_eq!(Shortcut::of(KeyCode::KeyZ), None);
    }
}
