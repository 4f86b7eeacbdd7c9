//! Zoom and pan of an image in a viewport: screen points per texel and
//! the texel at the viewport's centre, so zooming keeps the texel under
//! the cursor where it is.

use egui::{Pos2, Rect, Vec2, vec2};

/// The most texels a screen point may show, and the most points a texel
/// may cover.
const ZOOM: (f32, f32) = (1.0 / 64.0, 256.0);

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// Screen points per texel.
    pub zoom: f32,
    /// The texel coordinate (texel corners at whole numbers) at the centre.
    pub center: Vec2,
}

impl View {
    /// The whole image, as large as fits.
    pub fn fit(viewport: Vec2, [w, h]: [u32; 2]) -> View {
        let (w, h) = (w.max(1) as f32, h.max(1) as f32);
        let zoom = (viewport.x / w).min(viewport.y / h).clamp(ZOOM.0, ZOOM.1);
        View { zoom, center: vec2(w / 2.0, h / 2.0) }
    }

    /// Where the whole image lies on screen.
    pub fn image_rect(&self, viewport: Rect, [w, h]: [u32; 2]) -> Rect {
        let min = viewport.center() - self.center * self.zoom;
        Rect::from_min_size(min, vec2(w as f32, h as f32) * self.zoom)
    }

    /// The texel under screen position `at`, if it is one of the image's.
    pub fn texel_at(&self, viewport: Rect, size: [u32; 2], at: Pos2) -> Option<[u32; 2]> {
        let t = (at - viewport.center()) / self.zoom + self.center;
        let (x, y) = (t.x.floor(), t.y.floor());
        (x >= 0.0 && y >= 0.0 && x < size[0] as f32 && y < size[1] as f32).then_some([x as u32, y as u32])
    }

    /// Zooms by `factor` keeping the point under `at` still.
    pub fn zoom_about(&mut self, viewport: Rect, at: Pos2, factor: f32) {
        let before = (at - viewport.center()) / self.zoom + self.center;
        self.zoom = (self.zoom * factor).clamp(ZOOM.0, ZOOM.1);
        self.center = before - (at - viewport.center()) / self.zoom;
    }

    /// Moves the image by `delta` screen points.
    pub fn pan(&mut self, delta: Vec2) {
        self.center -= delta / self.zoom;
    }

    /// Centres texel `[x, y]` at `zoom` points per texel.
    pub fn centred_on([x, y]: [u32; 2], zoom: f32) -> View {
        View { zoom: zoom.clamp(ZOOM.0, ZOOM.1), center: vec2(x as f32 + 0.5, y as f32 + 0.5) }
    }
}

/// Where the centre of texel `[x, y]` lies on screen.
#[cfg(test)]
fn texel_centre(view: &View, viewport: Rect, [x, y]: [u32; 2]) -> Pos2 {
    viewport.center() + (vec2(x as f32 + 0.5, y as f32 + 0.5) - view.center) * view.zoom
}

#[cfg(test)]
mod tests {
    use super::*;
    use egui::pos2;

    fn viewport() -> Rect {
        Rect::from_min_size(pos2(10.0, 20.0), vec2(400.0, 200.0))
    }

    #[test]
    fn fitting_shows_the_whole_image_centred() {
        let v = View::fit(viewport().size(), [100, 100]);
        assert_eq!(v.zoom, 2.0);
        assert_eq!(v.image_rect(viewport(), [100, 100]), Rect::from_min_size(pos2(110.0, 20.0), vec2(200.0, 200.0)));
        assert_eq!(v.texel_at(viewport(), [100, 100], pos2(110.0, 20.0)), Some([0, 0]));
        assert_eq!(v.texel_at(viewport(), [100, 100], pos2(309.9, 219.9)), Some([99, 99]));
        assert_eq!(v.texel_at(viewport(), [100, 100], pos2(109.0, 20.0)), None, "left of the image");
    }

    #[test]
    fn zooming_keeps_the_texel_under_the_cursor() {
        let mut v = View::fit(viewport().size(), [100, 100]);
        let at = pos2(150.0, 60.0);
        let before = v.texel_at(viewport(), [100, 100], at);
        v.zoom_about(viewport(), at, 8.0);
        assert_eq!(v.zoom, 16.0);
        assert_eq!(v.texel_at(viewport(), [100, 100], at), before);
        let centre = texel_centre(&v, viewport(), before.unwrap());
        assert!((centre - at).length() <= 16.0, "{centre:?} {at:?}");
    }

    #[test]
    fn panning_moves_the_image_with_the_pointer() {
        let mut v = View::centred_on([10, 10], 4.0);
        let at = texel_centre(&v, viewport(), [10, 10]);
        v.pan(vec2(8.0, 0.0));
        assert_eq!(v.texel_at(viewport(), [100, 100], at), Some([8, 10]));
    }
}
