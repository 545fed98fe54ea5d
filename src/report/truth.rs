//! The ground-truth pictures in a report page: `shadow.png`, `flicker.png` and the animation
//! `shadow.apng` ([`crate::figures::truth`]), each with a caption saying what to look for.
//!
//! A page shows the still images inline (base64 data URIs, as the camera-view images of
//! [`html::png_figures`]); the animation inline when it is at most [`INLINE_ANIMATION_LIMIT`]
//! bytes, else as an `<img>` of the sibling file, so the page stays small. The scatter
//! `flicker_vs_shimmer` is an ordinary sweep figure (its SVG goes in the page's plots with
//! [`crate::figures::truth::FLICKER_VS_SHIMMER_CAPTION`]).

use std::fmt::Write as _;

use super::html;
use crate::figures::truth::SHADOW_APNG;

/// The largest animation embedded in a page; a larger one is shown from its file beside the page.
pub(crate) const INLINE_ANIMATION_LIMIT: usize = 2 << 20;

/// The animation as a page shows it.
#[derive(Debug, Clone, PartialEq)]
pub enum Animation {
    /// The APNG bytes, embedded.
    Bytes(Vec<u8>),
    /// The file (relative to the page) and its size in bytes, not embedded.
    File { href: String, bytes: u64 },
}

/// The pictures of one analysis, whichever were made.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TruthPictures {
    pub shadow_png: Option<Vec<u8>>,
    pub flicker_png: Option<Vec<u8>>,
    pub animation: Option<Animation>,
}

/// The caption of `shadow.png`.
pub(crate) fn shadow_caption(label: &str) -> String {
    format!(
        "{label}: the camera view as the shadow map shades it (shadow.png). Look for acne (magenta) on lit surfaces and leaks (cyan) where shadows should start at their casters; faces turned from the light are in shadow by their own orientation (grey-violet, no map is read for them); snapped on the left, unsnapped on the right."
    )
}

/// The caption of `flicker.png`.
pub(crate) fn flicker_caption(label: &str) -> String {
    format!(
        "{label}: how often each receiver pixel flipped between lit and shadowed along the path (flicker.png). Bright pixels flip often: at a shadow edge that crawls, or where acne comes and goes as the grid slides (summary.json splits S5 into flicker_edge_* and flicker_acne_*); with snapped windows they should stay dark."
    )
}

/// The caption of the animation.
pub(crate) fn animation_caption(label: &str) -> String {
    format!(
        "{label}: the path, every k-th frame ({SHADOW_APNG}). Watch the shadow edges: a crawl or shimmer along them is what players see; the bar under the titles is the position along the path. The pixels are the receivers of the first frame, followed along the path: as the camera moves, receivers leave the view (or every cascade) and turn to the no-receiver grey, a wedge that grows toward the end of the path; new ground coming into view is not drawn."
    )
}

/// The section's markup: a heading, the still images side by side, then the animation; empty
/// when there is no picture.
pub fn section(label: &str, p: &TruthPictures) -> String {
    let mut stills = Vec::new();
    if let Some(png) = &p.shadow_png {
        stills.push((png.clone(), shadow_caption(label)));
    }
    if let Some(png) = &p.flicker_png {
        stills.push((png.clone(), flicker_caption(label)));
    }
    if stills.is_empty() && p.animation.is_none() {
        return String::new();
    }
    let mut h = String::from("<h2>Shadow-map ground truth</h2>\n");
    if !stills.is_empty() {
        h.push_str(&html::png_figures(&stills));
    }
    if let Some(a) = &p.animation {
        let caption = animation_caption(label);
        let src = match a {
            Animation::Bytes(b) if b.len() <= INLINE_ANIMATION_LIMIT => {
                format!("data:image/apng;base64,{}", html::base64(b))
            }
            Animation::Bytes(_) => SHADOW_APNG.to_string(),
            Animation::File { href, .. } => href.clone(),
        };
        let note = match a {
            Animation::Bytes(b) if b.len() > INLINE_ANIMATION_LIMIT => {
                format!(
                    " ({SHADOW_APNG} beside this page, {} KiB, not inlined)",
                    b.len().div_ceil(1024)
                )
            }
            Animation::File { href, bytes } => format!(" ({href}, {} KiB, not inlined)", bytes.div_ceil(1024)),
            _ => String::new(),
        };
        let _ = writeln!(
            h,
            "<figure><img style=\"max-width: 100%\" alt=\"{0}\" src=\"{1}\"/><figcaption>{0}{2}</figcaption></figure>",
            html::escape(&caption),
            html::escape(&src),
            html::escape(&note)
        );
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nothing_to_show_gives_no_section() {
        assert_eq!(section("x", &TruthPictures::default()), "");
    }

    #[test]
    fn a_large_animation_is_linked_not_embedded() {
        let big = TruthPictures {
            animation: Some(Animation::Bytes(vec![7; INLINE_ANIMATION_LIMIT + 1])),
            ..Default::default()
        };
        let h = section("r", &big);
        assert!(h.contains("src=\"shadow.apng\""), "{h}");
        assert!(!h.contains("base64"));
        assert!(h.contains("2049 KiB, not inlined"), "{h}");
        let small = TruthPictures {
            animation: Some(Animation::Bytes(vec![1, 2, 3])),
            ..Default::default()
        };
        assert!(section("r", &small).contains("src=\"data:image/apng;base64,AQID\""));
    }
}
