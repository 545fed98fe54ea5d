//! Pictures of shadow state on the sampled screen grid: plain images that the ground-truth pass
//! fills and the figures draw.
//!
//! An image covers the visibility pass's grid (`cols × rows` samples of the screen), row-major,
//! row 0 at the top of the screen, column 0 at its left. A pixel whose surface faces away from
//! the light is [`Shade::Away`] (in shadow by its own orientation, whatever the map says); a
//! pixel without a receiver (sky, a point no cascade serves) is [`Shade::Empty`].

/// What one screen pixel shows, as the shadow map decides it, against the exact answer (a ray
/// from the surface point toward the light).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Shade {
    /// No receiver at this pixel.
    #[default]
    Empty,
    /// Lit, and truly lit.
    Lit,
    /// Shadowed, and truly shadowed.
    Shadowed,
    /// Shadowed by the map although the point is truly lit, every texel read holding its own
    /// surface (self-shadowing: acne).
    Acne,
    /// Wrong because the texels read hold another surface than the one the exact answer sees:
    /// the blocky shadow edge, in either direction.
    Edge,
    /// Lit by the map only because of the bias although the point is truly shadowed
    /// (peter-panning, light leaks).
    Leak,
    /// The surface faces away from the light (`N · L <= 0`): in shadow by its own orientation,
    /// so no shadow map is read for it and it is never acne or a leak.
    Away,
}

impl Shade {
    /// The state from the map's answer and the exact answer (both: is the point lit?), a wrong
    /// answer read as acne or a leak (the ground-truth pass tells edges apart).
    pub fn of(map_lit: bool, truly_lit: bool) -> Shade {
        match (map_lit, truly_lit) {
            (true, true) => Shade::Lit,
            (false, false) => Shade::Shadowed,
            (false, true) => Shade::Acne,
            (true, false) => Shade::Leak,
        }
    }
}

/// One frame's states over the sampled screen grid.
#[derive(Debug, Clone, PartialEq)]
pub struct ShadeImage {
    pub cols: u32,
    pub rows: u32,
    /// `cols × rows` states, row-major from the top-left pixel.
    pub pixels: Vec<Shade>,
}

impl ShadeImage {
    /// An image with no receiver anywhere.
    pub fn empty(cols: u32, rows: u32) -> Self {
        ShadeImage {
            cols,
            rows,
            pixels: vec![Shade::Empty; cols as usize * rows as usize],
        }
    }

    pub fn get(&self, col: u32, row: u32) -> Shade {
        self.pixels[row as usize * self.cols as usize + col as usize]
    }

    pub fn set(&mut self, col: u32, row: u32, shade: Shade) {
        self.pixels[row as usize * self.cols as usize + col as usize] = shade;
    }
}

/// How often each receiver pixel flipped between lit and shadowed along a path.
#[derive(Debug, Clone, PartialEq)]
pub struct FlipImage {
    pub cols: u32,
    pub rows: u32,
    /// Per pixel, row-major from the top left: the fraction of consecutive frame pairs in which
    /// the map's answer changed, in [0, 1]; None without a receiver.
    pub flips: Vec<Option<f64>>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn states_combine_the_two_answers() {
        assert_eq!(Shade::of(true, true), Shade::Lit);
        assert_eq!(Shade::of(false, false), Shade::Shadowed);
        assert_eq!(Shade::of(false, true), Shade::Acne);
        assert_eq!(Shade::of(true, false), Shade::Leak);
    }

    #[test]
    fn pixels_are_row_major_from_the_top_left() {
        let mut image = ShadeImage::empty(3, 2);
        image.set(2, 1, Shade::Leak);
        assert_eq!(image.pixels[5], Shade::Leak);
        assert_eq!(image.get(2, 1), Shade::Leak);
        assert_eq!(image.get(0, 0), Shade::Empty);
    }
}
