//! `TextAnimator`: sentences (Japanese or English) → the motion time table of spec §H → one
//! joined and composed animation (§I), added to a `Library` so the viewer plays it.

use odori_core::actions::ActionLibrary;
use odori_core::text::{self, TextAnimation, TimeTableElement};
use serde::Serialize;
use wasm_bindgen::prelude::*;

use crate::error::{to_js, OdoriError};
use crate::library::Library;

#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct Result_<'a> {
    clip_id: u32,
    elements: &'a [TimeTableElement],
    diagnostics: &'a [text::Diagnostic],
    duration_secs: f32,
}

/// The action library and the text → animation pipeline.
#[wasm_bindgen]
pub struct TextAnimator {
    actions: ActionLibrary,
}

impl Default for TextAnimator {
    fn default() -> Self {
        Self::new()
    }
}

impl TextAnimator {
    fn publish(&self, library: &mut Library, anim: TextAnimation, replace: Option<u32>) -> JsValue {
        let duration_secs = anim.clip.duration_secs();
        let mut clip = anim.clip;
        clip.source = "text".into();
        let id = library.insert_clip(clip, "text", replace);
        to_js(&Result_ { clip_id: id, elements: &anim.elements, diagnostics: &anim.diagnostics, duration_secs })
    }
}

#[wasm_bindgen]
impl TextAnimator {
    /// The built-in everyday actions (walk, run, kick, jump, wave, clap, rejoice, gutsy pose,
    /// turn, bow, sit, stand, nod, point ...).
    #[wasm_bindgen(constructor)]
    pub fn new() -> TextAnimator {
        TextAnimator { actions: ActionLibrary::builtin() }
    }

    /// Makes a library clip usable by name and by these tags ("dance", "踊る").
    #[wasm_bindgen(js_name = tagClip)]
    pub fn tag_clip(&mut self, library: &Library, clip_id: u32, tags: Vec<String>) -> Result<usize, OdoriError> {
        let e = library.entry(clip_id)?;
        self.actions.add_clip(&e.clip, &tags, None).map_err(|err| OdoriError::new("text", err.to_string()))
    }

    /// Name of action `index` (the `clip` / `alternatives` numbers of the time table).
    #[wasm_bindgen(js_name = actionName)]
    pub fn action_name(&self, index: usize) -> Option<String> {
        self.actions.get(index).map(|a| a.name.clone())
    }

    /// Parses and animates `text`. The animation is added to `library` (replacing clip
    /// `replace` when given); returns `{ clipId, elements, diagnostics, durationSecs }`.
    /// Unknown verbs come back as diagnostics with their positions and the rest still plays;
    /// a text with nothing to play throws an `OdoriError` of kind "text".
    pub fn animate(&self, library: &mut Library, text: &str, replace: Option<u32>) -> Result<JsValue, OdoriError> {
        let anim = text::animate_text(text, &self.actions).map_err(|e| OdoriError::new("text", e.to_string()))?;
        Ok(self.publish(library, anim, replace))
    }

    /// Re-animates an edited time table (e.g. an element's `clip` swapped for one of its
    /// `alternatives`). An element whose `clip` is not an index of the action library is
    /// refused with a "not-found" error (it is not replaced by the default silently).
    #[wasm_bindgen(js_name = animateTable)]
    pub fn animate_table(&self, library: &mut Library, elements: JsValue, replace: Option<u32>) -> Result<JsValue, OdoriError> {
        let table: Vec<TimeTableElement> =
            serde_wasm_bindgen::from_value(elements).map_err(|e| OdoriError::new("bad-argument", format!("time table: {e}")))?;
        let anim = text::animate_table(&table, &self.actions, Vec::new()).map_err(|e| match e {
            text::TextError::NoSuchClip { .. } => OdoriError::new("not-found", e.to_string()),
            e => OdoriError::new("text", e.to_string()),
        })?;
        Ok(self.publish(library, anim, replace))
    }
}
