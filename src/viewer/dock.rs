//! The viewer's right-hand dock: the error heatmap, the technique's debug
//! views and the help, and the technique's debug images as textures.

use super::ViewerState;
use crate::technique;

const HELP: &str = "\
Mouse: left drag orbits (or drags a light icon), middle drag or wheel zooms, right drag pans.
Keys: W/A/S/D fly, Q/E down/up; arrows and PageUp/PageDown move the selected light;
0-3 select light 0-3; M toggles the mask view; H computes the error heatmap against
raytraced; P or F12 saves a screenshot (shadowlab-<time>.png and .json beside it); Tab hides the panel;
F1 this help; Esc closes this dock, and quits when no dock is open. Keys act on the view unless a
text field has the focus; drags that start on a panel or the dock do not move the camera.";

/// Below this width (points) the side panel starts folded to its toggle
/// and the dock starts collapsed, leaving the view to the image.
pub const SMALL_WINDOW: f32 = 800.0;

/// The right-hand dock: the error heatmap, the technique's debug views and
/// the help, one collapsible section each, in one scrollable window
/// anchored to the window's right edge — over the 3D view, never over the
/// side panel's controls.
pub fn show(root: &mut egui::Ui, state: &mut ViewerState) {
    state.dock_rect = None;
    if !state.dock_open() {
        return;
    }
    let debug = state.show_debug && !state.debug_images.is_empty();
    let ctx = root.ctx().clone();
    let screen = ctx.content_rect();
    let width = (screen.width() * 0.32).clamp(160.0, 360.0);
    let mut close_heatmap = false;
    let shown = egui::Window::new("views")
        .anchor(egui::Align2::RIGHT_TOP, [-8.0, 8.0])
        .default_width(width)
        .max_width(width)
        .max_height(screen.height() - 16.0)
        .collapsible(true)
        .default_open(screen.width() >= SMALL_WINDOW)
        .resizable(false)
        .show(&ctx, |ui| {
            egui::ScrollArea::vertical()
                .max_height(screen.height() - 64.0)
                .show(ui, |ui| {
                    let image_width = ui.available_width();
                    if let Some(h) = &state.heatmap {
                        egui::CollapsingHeader::new("Error heatmap vs raytraced")
                            .default_open(true)
                            .show(ui, |ui| {
                                ui.label(&h.summary);
                                ui.label("red: false shadow, blue: false lit");
                                let size = h.texture.size_vec2();
                                ui.image((h.texture.id(), size * (image_width / size.x).min(1.0)));
                                close_heatmap = ui.button("close").clicked();
                            });
                    }
                    if debug {
                        egui::CollapsingHeader::new("Technique debug views")
                            .default_open(true)
                            .show(ui, |ui| {
                                for (label, texture) in &state.debug_images {
                                    ui.label(label);
                                    let size = texture.size_vec2();
                                    ui.image((
                                        texture.id(),
                                        size * (image_width / size.x).min(1.0),
                                    ));
                                }
                            });
                    }
                    if state.show_help {
                        egui::CollapsingHeader::new("Help")
                            .default_open(true)
                            .show(ui, |ui| {
                                ui.label(HELP);
                                if ui.button("close").clicked() {
                                    state.show_help = false;
                                }
                            });
                    }
                });
        });
    state.dock_rect = shown.map(|r| r.response.rect * ctx.pixels_per_point());
    if close_heatmap {
        state.heatmap = None;
    }
}

/// A technique's debug images as egui textures, with their labels.
pub fn debug_textures(
    ctx: &egui::Context,
    images: Vec<technique::DebugImage>,
) -> Vec<(String, egui::TextureHandle)> {
    images
        .into_iter()
        .map(|im| {
            let img = egui::ColorImage::from_rgba_unmultiplied(
                [im.width as usize, im.height as usize],
                &im.rgba,
            );
            let texture = ctx.load_texture("technique debug", img, egui::TextureOptions::LINEAR);
            (im.label, texture)
        })
        .collect()
}
