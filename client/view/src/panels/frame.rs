//! The Frame panel: the newest finished frame, zero-copy: the daemon's
//! display texture registered with egui's renderer, scaled to fit with its
//! aspect kept.

use crate::link::DisplayImage;

/// A display texture as egui knows it.
pub struct FrameTexture {
    id: Option<egui::TextureId>,
    generation: Option<u64>,
    /// Linear for a frame scaled to fit; nearest for texels zoomed into.
    filter: wgpu::FilterMode,
}

impl FrameTexture {
    pub fn new(filter: wgpu::FilterMode) -> Self {
        FrameTexture { id: None, generation: None, filter }
    }

    /// Its id once registered.
    pub fn id(&self) -> Option<egui::TextureId> {
        self.id
    }

    /// Registers `image` with the renderer, or points the registered id at
    /// it when the daemon replaced its texture.
    pub fn sync(&mut self, image: &DisplayImage, render: &egui_wgpu::RenderState) {
        if self.generation == Some(image.generation) {
            return;
        }
        let mut renderer = render.renderer.write();
        match self.id {
            Some(id) => renderer.update_egui_texture_from_wgpu_texture(&render.device, &image.view, self.filter, id),
            None => self.id = Some(renderer.register_native_texture(&render.device, &image.view, self.filter)),
        }
        self.generation = Some(image.generation);
    }

    /// Draws the frame into the space left; returns whether a frame would
    /// be on screen there (not when that space is empty), so the daemon
    /// copies frames exactly while they can be seen.
    pub fn show(&self, ui: &mut egui::Ui, image: Option<&DisplayImage>) -> bool {
        let room = ui.available_size();
        if room.x < 1.0 || room.y < 1.0 {
            return false;
        }
        match (self.id, image) {
            (Some(id), Some(image)) => {
                let size = fit(room, image.size);
                ui.centered_and_justified(|ui| ui.add(egui::Image::new((id, size)).fit_to_exact_size(size)));
            }
            _ => {
                ui.centered_and_justified(|ui| ui.label("waiting for the first frame"));
            }
        }
        true
    }
}

/// The largest size of `image`'s aspect inside `space`.
pub fn fit(space: egui::Vec2, image: [u32; 2]) -> egui::Vec2 {
    let (w, h) = (image[0].max(1) as f32, image[1].max(1) as f32);
    let scale = (space.x / w).min(space.y / h).max(0.0);
    egui::vec2(w * scale, h * scale)
}

#[cfg(test)]
mod tests {
    use super::fit;

    #[test]
    fn the_aspect_is_kept_inside_the_space() {
        assert_eq!(fit(egui::vec2(400.0, 400.0), [200, 100]), egui::vec2(400.0, 200.0));
        assert_eq!(fit(egui::vec2(400.0, 100.0), [200, 100]), egui::vec2(200.0, 100.0));
        assert_eq!(fit(egui::vec2(0.0, 100.0), [200, 100]), egui::vec2(0.0, 0.0));
    }
}
