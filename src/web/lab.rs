//! The lab's JavaScript interface: `web/main.js` creates a [`Lab`] on the
//! page's canvas and calls it per frame, per control and per comparison.
//! Calls that await (a frame's readback, a comparison, a new technique or
//! file) return promises; a call that finds the page held by an awaited
//! one is refused as busy, except a frame, which is skipped.

use super::page::{Page, Presented, Shown, unavailable};
use super::present::PresentMode;
use super::readback::map_read;
use crate::scene::orbit;
use crate::technique;
use std::cell::RefCell;
use std::rc::Rc;
use wasm_bindgen::prelude::*;

/// The page's lab; JavaScript calls its methods (`web/main.js`).
#[wasm_bindgen]
pub struct Lab {
    page: Rc<RefCell<Page>>,
}

fn js_error(e: anyhow::Error) -> JsValue {
    JsValue::from_str(&format!("{e:#}"))
}

/// The page, or an error while a comparison (or another awaited call)
/// holds it.
fn borrow(page: &RefCell<Page>) -> Result<std::cell::RefMut<'_, Page>, JsValue> {
    page.try_borrow_mut()
        .map_err(|_| JsValue::from_str("busy: a comparison is running"))
}

/// Awaits what presenting left: the 2D canvas's readback, or the shown
/// mask's, which is then drawn (skipped when an awaited call holds the
/// page meanwhile).
async fn finish(page: &RefCell<Page>, presented: Presented) -> anyhow::Result<()> {
    let draw = match presented {
        Presented::Drawn => None,
        Presented::Draw(d) => Some(d),
        Presented::Mask(copy) => {
            let raw = copy.unpad(&map_read(&copy.buffer).await?);
            match page.try_borrow() {
                Ok(p) => p.present_mask(&raw)?,
                Err(_) => None,
            }
        }
    };
    match draw {
        Some(d) => d.draw().await,
        None => Ok(()),
    }
}

impl Lab {
    fn page(&self) -> Result<std::cell::RefMut<'_, Page>, JsValue> {
        borrow(&self.page)
    }

    /// Moves the camera by `f`. A heatmap is of the frame compared: once
    /// the camera moves, the image is shown instead (a mask view follows
    /// the camera).
    fn move_camera(&self, f: impl FnOnce(&mut crate::scene::Camera)) -> Result<(), JsValue> {
        let mut p = self.page()?;
        f(&mut p.camera);
        if matches!(p.shown, Shown::Heatmap(_)) {
            p.shown = Shown::Image;
        }
        Ok(())
    }
}

#[wasm_bindgen]
impl Lab {
    /// The lab on `canvas` for the URL's parameters (`pairs`: a JSON array
    /// of `[key, value]`, already decoded), presenting as `present` says
    /// (`webgpu` or `readback`).
    pub async fn create(
        canvas: web_sys::HtmlCanvasElement,
        pairs: String,
        present: String,
    ) -> Result<Lab, JsValue> {
        let present = PresentMode::parse(&present).map_err(js_error)?;
        let page = Page::create(canvas, &pairs, present)
            .await
            .map_err(js_error)?;
        Ok(Lab {
            page: Rc::new(RefCell::new(page)),
        })
    }

    /// Renders and shows one frame; resolves to its CPU time in ms (0 while
    /// a comparison runs).
    pub fn frame(&self) -> js_sys::Promise {
        let page = self.page.clone();
        wasm_bindgen_futures::future_to_promise(async move {
            let (ms, presented) = {
                let Ok(mut p) = page.try_borrow_mut() else {
                    return Ok(JsValue::from_f64(0.0));
                };
                let ms = p.render().map_err(js_error)?;
                (ms, p.present().map_err(js_error)?)
            };
            finish(&page, presented).await.map_err(js_error)?;
            Ok(JsValue::from_f64(ms))
        })
    }

    /// Compares the frame with the reference; resolves to a JSON report.
    pub fn compare(&self) -> js_sys::Promise {
        let page = self.page.clone();
        wasm_bindgen_futures::future_to_promise(async move {
            let mut p = borrow(&page)?;
            let report = p.compare().await.map_err(js_error)?;
            let presented = p.present().map_err(js_error)?;
            drop(p);
            finish(&page, presented).await.map_err(js_error)?;
            Ok(JsValue::from_str(&report.to_string()))
        })
    }

    /// Switches light `light` (every light: `undefined`) to technique
    /// `spec` (`family:preset[key=value,...]`).
    pub fn set_technique(&self, spec: String, light: Option<usize>) -> js_sys::Promise {
        let page = self.page.clone();
        wasm_bindgen_futures::future_to_promise(async move {
            let mut p = borrow(&page)?;
            let choice = technique::parse_choice(&spec).map_err(js_error)?;
            p.set_choice(choice, light).await.map_err(js_error)?;
            Ok(JsValue::UNDEFINED)
        })
    }

    /// Sets one parameter of light `light`'s technique's table (every
    /// light's: `undefined`), as `--set key=value` does.
    pub fn set_param(&self, key: String, value: String, light: Option<usize>) -> js_sys::Promise {
        let page = self.page.clone();
        wasm_bindgen_futures::future_to_promise(async move {
            let mut p = borrow(&page)?;
            let mut choice = p.choice(light.unwrap_or(0)).clone();
            choice.params.set(&key, &value).map_err(js_error)?;
            p.set_choice(choice, light).await.map_err(js_error)?;
            Ok(JsValue::UNDEFINED)
        })
    }

    /// The technique's table: every row (name, kind, default, min, max,
    /// step, doc), its current value and whether it applies to each light.
    pub fn parameters(&self, light: Option<usize>) -> Result<String, JsValue> {
        let p = self.page()?;
        let choice = p.choice(light.unwrap_or(0));
        let params = &choice.params;
        let rows: Vec<serde_json::Value> = params
            .specs
            .iter()
            .zip(&params.values)
            .map(|(spec, &v)| {
                let applies: Vec<bool> = p
                    .lights
                    .iter()
                    .map(|l| params.applies(spec, Some(l.kind)))
                    .collect();
                serde_json::json!({"spec": spec, "value": spec.format(v), "applies": applies})
            })
            .collect();
        Ok(
            serde_json::json!({"technique": choice.id(), "all": p.technique_label(), "rows": rows})
                .to_string(),
        )
    }

    /// Every preset, with why it does not run in the page where it does not.
    pub fn techniques() -> String {
        let rows: Vec<serde_json::Value> = technique::preset_ids()
            .into_iter()
            .map(|id| {
                let family = id.split(':').next().unwrap_or_default().to_string();
                serde_json::json!({"id": id, "unavailable": unavailable(&family)})
            })
            .collect();
        serde_json::Value::from(rows).to_string()
    }

    /// Built-in scene names.
    pub fn scenes() -> String {
        serde_json::json!(crate::scene::builtin::NAMES).to_string()
    }

    /// Orbits the camera by `dx`, `dy` radians (yaw, pitch).
    pub fn orbit(&self, dx: f32, dy: f32) -> Result<(), JsValue> {
        self.move_camera(|c| orbit::orbit(c, dx, dy))
    }

    /// Moves the camera towards (`factor` < 1) or away from its target.
    pub fn zoom(&self, factor: f32) -> Result<(), JsValue> {
        self.move_camera(|c| orbit::zoom(c, factor))
    }

    /// Pans by fractions of the distance to the target.
    pub fn pan(&self, dx: f32, dy: f32) -> Result<(), JsValue> {
        self.move_camera(|c| orbit::pan(c, dx, dy))
    }

    /// Shows light `light`'s visibility mask in grey (white = lit).
    pub fn show_mask(&self, light: usize) -> Result<(), JsValue> {
        let mut p = self.page()?;
        p.check_light(light).map_err(js_error)?;
        p.shown = Shown::Mask(light);
        Ok(())
    }

    /// The number of lights (for the mask view's choice).
    pub fn light_count(&self) -> Result<usize, JsValue> {
        Ok(self.page()?.lights.len())
    }

    /// The lights as JSON (type, position, direction, colour, intensity,
    /// range, cones, area), as a TOML scene writes them.
    pub fn lights(&self) -> Result<String, JsValue> {
        serde_json::to_string(&self.page()?.lights).map_err(|e| JsValue::from_str(&e.to_string()))
    }

    /// Replaces light `index` by `json` (one entry of [`Lab::lights`]).
    pub fn set_light(&self, index: usize, json: String) -> Result<(), JsValue> {
        let light: crate::scene::Light = serde_json::from_str(&json)
            .map_err(|e| JsValue::from_str(&format!("light {index}: {e}")))?;
        self.page()?.set_light(index, light).map_err(js_error)
    }

    /// Shows the rendered image again instead of the heatmap.
    pub fn show_image(&self) -> Result<(), JsValue> {
        self.page()?.shown = Shown::Image;
        Ok(())
    }

    /// The query string that reproduces the view shown.
    pub fn link(&self) -> Result<String, JsValue> {
        self.page()?.link().map_err(js_error)
    }

    /// Opens a glTF, GLB or OBJ file's bytes as the scene.
    pub fn load_file(&self, name: String, bytes: Vec<u8>) -> js_sys::Promise {
        let page = self.page.clone();
        wasm_bindgen_futures::future_to_promise(async move {
            let mut p = borrow(&page)?;
            p.open(&name, &bytes).await.map_err(js_error)?;
            Ok(JsValue::UNDEFINED)
        })
    }

    /// Light `light`'s mask of the last comparison, one byte a pixel
    /// (255 = lit), rows top first, in base64: what the test suite compares
    /// with the native build's mask of the same frame.
    pub fn compared_mask(&self, light: usize) -> Result<String, JsValue> {
        use base64::Engine as _;
        let p = self.page()?;
        let mask = p
            .compared_masks
            .get(light)
            .ok_or_else(|| JsValue::from_str("no comparison of that light has run"))?;
        Ok(base64::engine::general_purpose::STANDARD.encode(crate::headless::mask_to_u8(mask)))
    }

    /// The adapter's name, type and backend.
    pub fn adapter(&self) -> Result<String, JsValue> {
        Ok(self.page()?.gpu.adapter_summary())
    }
}
