//! The viewer's input: window events, keys and mouse, and the camera and
//! lights they move each frame.

use super::{App, Overlay, PathMotion, orbit};
use crate::measure::flicker::path_camera;
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
        let consumed = gfx.egui_state.on_window_event(&gfx.window, &event).consumed;
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw(event_loop) {
                    self.exit_error = Some(e);
                    event_loop.exit();
                }
            }
            WindowEvent::KeyboardInput { event, .. } => {
                let PhysicalKey::Code(code) = event.physical_key else {
                    return;
                };
                if event.state == ElementState::Pressed {
                    if !consumed && !gfx.egui_ctx.egui_wants_keyboard_input() {
                        self.keys.insert(code);
                        match code {
                            KeyCode::F12 | KeyCode::KeyP => self.state.screenshot_requested = true,
                            KeyCode::F1 => self.state.show_help = !self.state.show_help,
                            KeyCode::Tab => self.state.show_panel = !self.state.show_panel,
                            KeyCode::KeyM => {
                                self.state.overlay = match self.state.overlay {
                                    Overlay::Image => Overlay::Mask(self.state.selected_light),
                                    Overlay::Mask(_) => Overlay::Image,
                                }
                            }
                            KeyCode::KeyH => self.start_heatmap(),
                            KeyCode::Digit0
                            | KeyCode::Digit1
                            | KeyCode::Digit2
                            | KeyCode::Digit3 => {
                                // Lights count from 0, as everywhere.
                                let i = match code {
                                    KeyCode::Digit0 => 0,
                                    KeyCode::Digit1 => 1,
                                    KeyCode::Digit2 => 2,
                                    _ => 3,
                                };
                                if self.scene.as_ref().is_some_and(|s| i < s.lights.len()) {
                                    self.state.selected_light = i;
                                }
                            }
                            KeyCode::Escape => event_loop.exit(),
                            _ => {}
                        }
                    }
                } else {
                    self.keys.remove(&code);
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                // Cursor relative to the 3D view (right of the panel).
                let p = Vec2::new(
                    position.x as f32 - self.state.view_left as f32,
                    position.y as f32,
                );
                let d = p - self.cursor;
                self.cursor = p;
                let size = gfx.window.inner_size();
                let sz = Vec2::new(
                    size.width.saturating_sub(self.state.view_left).max(1) as f32,
                    size.height.max(1) as f32,
                );
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
            WindowEvent::MouseInput { state, button, .. } => {
                let i = match button {
                    MouseButton::Left => 0,
                    MouseButton::Middle => 1,
                    MouseButton::Right => 2,
                    _ => return,
                };
                let pressed = state == ElementState::Pressed;
                if pressed && consumed {
                    return;
                }
                self.buttons[i] = pressed;
                if !pressed {
                    self.dragging_light = None;
                } else if i == 0 {
                    // Grab a light icon within 16 px of the cursor.
                    let size = gfx.window.inner_size();
                    let sz = Vec2::new(
                        size.width.saturating_sub(self.state.view_left).max(1) as f32,
                        size.height.max(1) as f32,
                    );
                    if let Some(s) = &self.scene {
                        let vp = s.camera.projection(sz.x / sz.y) * s.camera.view();
                        self.dragging_light = s.lights.iter().position(|l| {
                            l.kind != crate::scene::LightType::Directional
                                && orbit::project(vp, sz, l.position)
                                    .is_some_and(|q| q.distance(self.cursor) < 16.0)
                        });
                        if let Some(li) = self.dragging_light {
                            self.state.selected_light = li;
                        }
                    }
                }
            }
            WindowEvent::MouseWheel { delta, .. } if !consumed => {
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
