//! The ground-truth pictures (`shadow.png`, `flicker.png`, `shadow.apng`, `flicker_vs_shimmer`)
//! decoded and checked pixel by pixel against the layout and colours computed here, the
//! scatter's fit against sums computed here, and the report section parsed as XML.

use csm_core::shade::{FlipImage, Shade, ShadeImage};
use csm_lab::figures::truth::{
    self, colours, fit, flicker_png, flip_scale_max, ranks, shadow_png, write_animation, AnimationPlan,
    FlickerVsShimmer, Panel, ShimmerPoint, ANIMATION_CAPS, SHADES,
};
use csm_lab::figures::Figure;
use csm_lab::report::truth::{section, Animation, TruthPictures};

use crate::common::unbase64;

/// A decoded RGB8 image.
struct Rgb {
    w: u32,
    h: u32,
    px: Vec<u8>,
}

impl Rgb {
    fn at(&self, x: u32, y: u32) -> [u8; 3] {
        let o = ((y * self.w + x) * 3) as usize;
        [self.px[o], self.px[o + 1], self.px[o + 2]]
    }
}

fn decoder(bytes: &[u8]) -> png::Reader<&[u8]> {
    let mut d = png::Decoder::new(bytes);
    d.set_transformations(png::Transformations::EXPAND);
    d.read_info().expect("a PNG")
}

fn decode(bytes: &[u8]) -> Rgb {
    let mut r = decoder(bytes);
    let mut buf = vec![0; r.output_buffer_size()];
    let info = r.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf.truncate(info.buffer_size());
    Rgb {
        w: info.width,
        h: info.height,
        px: buf,
    }
}

const TITLE_H: u32 = 30;
const GAP: u32 = 16;

/// Pixel centre of grid cell (c, r) in panel i, panels `pw` wide enlarged by `k`, under the titles.
fn centre(i: u32, pw: u32, k: u32, c: u32, r: u32) -> (u32, u32) {
    (i * (pw + GAP) + c * k + k / 2, TITLE_H + r * k + k / 2)
}

fn state_rgb(s: Shade) -> [u8; 3] {
    match s {
        Shade::Empty => [236, 236, 236],
        Shade::Lit => [246, 222, 140],
        Shade::Shadowed => [72, 84, 112],
        Shade::Acne => [213, 40, 120],
        Shade::Edge => [240, 130, 20],
        Shade::Leak => [0, 190, 220],
        Shade::Away => [118, 116, 136],
    }
}

/// An 8 × 4 image with every state, shifted by `shift` so two panels differ.
fn synthetic(shift: usize) -> ShadeImage {
    let mut im = ShadeImage::empty(8, 4);
    for (k, p) in im.pixels.iter_mut().enumerate() {
        *p = SHADES[(k * 5 + shift) % 7];
    }
    im
}

#[test]
fn shadow_png_colours_each_pixel_by_its_state_side_by_side() {
    let (a, b) = (synthetic(0), synthetic(2));
    let png = shadow_png(&[Panel::snapped(&a), Panel::unsnapped(&b)]).unwrap();
    let img = decode(&png);
    // Two panels in 1280 pixels: (1280 - 16) / 2 = 632 per panel, 8 columns: k = 79.
    let k = 79;
    let pw = 8 * k;
    assert_eq!(img.w, 2 * pw + GAP);
    assert!(img.w <= 1280);
    for (i, im) in [&a, &b].into_iter().enumerate() {
        for r in 0..4 {
            for c in 0..8 {
                let (x, y) = centre(i as u32, pw, k, c, r);
                assert_eq!(img.at(x, y), state_rgb(im.get(c, r)), "panel {i} cell ({c}, {r})");
                // Nearest-neighbour: the cell's corners too.
                let (x0, y0) = (i as u32 * (pw + GAP) + c * k, TITLE_H + r * k);
                assert_eq!(img.at(x0, y0), img.at(x0 + k - 1, y0 + k - 1));
            }
        }
    }
    // The gap between the panels is white.
    assert_eq!(img.at(pw + GAP / 2, TITLE_H + 10), [255, 255, 255]);
    // The panel ends at 4 k rows; the legend is below it.
    assert!(img.h > TITLE_H + 4 * k);
    // One panel alone takes the whole width: 1280 / 8 = 160 per cell.
    let one = decode(&shadow_png(&[Panel::snapped(&a)]).unwrap());
    assert_eq!(one.w, 1280);
    let (x, y) = centre(0, 1280, 160, 3, 2);
    assert_eq!(one.at(x, y), state_rgb(a.get(3, 2)));
}

#[test]
fn shadow_png_of_the_default_scene_receivers() {
    // The stand-in of the truth pass: the visibility pass of configs/default.toml, pixels lit or
    // shadowed by the pass's own `lit` flag (facing the light or not); the second panel marks
    // every 7th lit pixel as acne and every 5th shadowed one as a leak.
    let cfg = csm_lab::Config::load(std::path::Path::new("configs/default.toml")).unwrap();
    let vis = cfg.setup().visibility().expect("the default scene has geometry");
    let (cols, rows) = (vis.cols, vis.rows);
    assert_eq!((cols, rows), (240, 135));
    let mut snapped = ShadeImage::empty(cols, rows);
    let mut unsnapped = ShadeImage::empty(cols, rows);
    for (k, s) in vis.samples.iter().enumerate() {
        let (c, r) = (k as u32 % cols, k as u32 / cols);
        if let Some(s) = s {
            snapped.set(c, r, if s.lit { Shade::Lit } else { Shade::Shadowed });
            let u = match (s.lit, k % 7 == 0, k % 5 == 0) {
                (true, true, _) => Shade::Acne,
                (false, _, true) => Shade::Leak,
                (l, _, _) => Shade::of(l, l),
            };
            unsnapped.set(c, r, u);
        }
    }
    let png = shadow_png(&[Panel::snapped(&snapped), Panel::unsnapped(&unsnapped)]).unwrap();
    let img = decode(&png);
    // 632 / 240 = 2, 900 / 135 = 6: k = 2.
    let (k, pw) = (2, 480);
    assert_eq!(img.w, 2 * pw + GAP);
    for r in (0..rows).step_by(7) {
        for c in (0..cols).step_by(11) {
            let (x, y) = centre(0, pw, k, c, r);
            assert_eq!(img.at(x, y), state_rgb(snapped.get(c, r)));
            let (x, y) = centre(1, pw, k, c, r);
            assert_eq!(img.at(x, y), state_rgb(unsnapped.get(c, r)));
        }
    }
    // Every state is in the picture.
    let n = |im: &ShadeImage, s: Shade| im.pixels.iter().filter(|p| **p == s).count();
    for s in [Shade::Empty, Shade::Lit, Shade::Shadowed] {
        assert!(n(&snapped, s) > 0, "{s:?}");
    }
    assert!(n(&unsnapped, Shade::Acne) > 0 && n(&unsnapped, Shade::Leak) > 0);
    assert_eq!(
        png,
        shadow_png(&[Panel::snapped(&snapped), Panel::unsnapped(&unsnapped)]).unwrap()
    );
    if let Ok(dir) = std::env::var("CSM_LAB_PICTURES_OUT") {
        std::fs::write(format!("{dir}/shadow.png"), &png).unwrap();
    }
    // The same scene along a 240-frame path in which the unsnapped panel's acne pattern moves
    // by one pixel per frame: a realistic animation, far under its byte bound.
    let plan = AnimationPlan::new(240, cols, rows, &["snapped", "unsnapped"], &ANIMATION_CAPS).unwrap();
    let moving = |f: usize| {
        let mut u = snapped.clone();
        for (k, p) in u.pixels.iter_mut().enumerate() {
            if *p == Shade::Lit && (k + f) % 7 == 0 {
                *p = Shade::Acne;
            }
        }
        vec![snapped.clone(), u]
    };
    let mut apng = Vec::new();
    write_animation(&plan, (0..240).map(moving), &mut apng).unwrap();
    let d = decode_animation(&apng);
    assert_eq!((d.num_frames, d.width), (48, 976));
    assert!((apng.len() as u64) < plan.byte_bound() / 4, "{} bytes", apng.len());
    if let Ok(dir) = std::env::var("CSM_LAB_PICTURES_OUT") {
        std::fs::write(format!("{dir}/shadow.apng"), &apng).unwrap();
        let mut last = Vec::new();
        let mut enc = png::Encoder::new(&mut last, d.width, d.height);
        enc.set_color(png::ColorType::Rgb);
        enc.write_header().unwrap().write_image_data(&d.last).unwrap();
        std::fs::write(format!("{dir}/shadow_apng_last.png"), &last).unwrap();
    }
}

/// Faces turned from the light are drawn in a shade of their own, not as "no receiver": the
/// pixels the visibility pass hits facing away from the light, exactly.
#[test]
fn faces_turned_from_the_light_are_drawn_as_away_not_as_sky() {
    let cfg = csm_lab::Config::load(std::path::Path::new("configs/default.toml")).unwrap();
    let vis = cfg.setup().visibility().expect("the default scene has geometry");
    let away = csm_core::truth::away_pixels(&vis);
    // Independently: every hit whose surface faces away from the light.
    let want: Vec<usize> = (0..vis.samples.len())
        .filter(|&i| vis.samples.get(i).is_some_and(|s| !s.lit))
        .collect();
    assert_eq!(away, want);
    assert_eq!(away.len(), vis.self_shadowed);
    assert!(
        !away.is_empty(),
        "the default scene's buildings have faces turned from the sun"
    );
    // No answers at all: only the away pixels are drawn, the rest is "no receiver".
    let image = csm_core::truth::shade_image(vis.cols, vis.rows, &away, &[], &[], &[]);
    for (i, p) in image.pixels.iter().enumerate() {
        let expected = if away.binary_search(&i).is_ok() {
            Shade::Away
        } else {
            Shade::Empty
        };
        assert_eq!(*p, expected, "pixel {i}");
    }
    let img = decode(&shadow_png(&[Panel::snapped(&image)]).unwrap());
    let k = (1280 / vis.cols).min(900 / vis.rows);
    let i = away[away.len() / 2];
    let (c, r) = (i as u32 % vis.cols, i as u32 / vis.cols);
    let (x, y) = centre(0, vis.cols * k, k, c, r);
    assert_eq!(img.at(x, y), state_rgb(Shade::Away));
    assert_ne!(state_rgb(Shade::Away), state_rgb(Shade::Empty));
    assert_ne!(state_rgb(Shade::Away), state_rgb(Shade::Shadowed));
}

#[test]
fn a_narrow_grid_leaves_room_for_the_legend() {
    // 10 × 100: k = min(1280 / 10, 900 / 100) = 9, a 90-pixel panel left-aligned in 960.
    let mut im = ShadeImage::empty(10, 100);
    for (k, p) in im.pixels.iter_mut().enumerate() {
        *p = SHADES[k % 6];
    }
    let img = decode(&shadow_png(&[Panel::snapped(&im)]).unwrap());
    assert_eq!(img.w, 960);
    assert_eq!(img.h, TITLE_H + 900 + 96);
    let (x, y) = centre(0, 90, 9, 3, 50);
    assert_eq!(img.at(x, y), state_rgb(im.get(3, 50)));
    assert_eq!(img.at(500, TITLE_H + 450), [255, 255, 255]);
}

#[test]
fn shadow_png_refuses_mismatched_panels() {
    let e = shadow_png(&[
        Panel::snapped(&synthetic(0)),
        Panel::unsnapped(&ShadeImage::empty(4, 4)),
    ])
    .unwrap_err()
    .to_string();
    assert!(e.contains("'unsnapped' is 4 × 4") && e.contains("8 × 4"), "{e}");
    assert!(shadow_png(&[]).unwrap_err().to_string().contains("no image"));
}

/// The viridis-like stops of the colour scale, at 0, 1/2 and 1.
const LOW: [u8; 3] = [68, 1, 84];
const MID: [u8; 3] = [33, 145, 140];
const HIGH: [u8; 3] = [253, 231, 37];
/// The colour bar's first and last steps (t = 1/180 and 179/180 between the stops).
const BAR_FIRST: [u8; 3] = [68, 3, 85];
const BAR_LAST: [u8; 3] = [249, 230, 38];

fn flips(values: &[Option<f64>]) -> FlipImage {
    FlipImage {
        cols: 4,
        rows: 2,
        flips: values.to_vec(),
    }
}

/// Whether a colour appears in the rows of `img` from `y0` down.
fn has_colour_below(img: &Rgb, y0: u32, c: [u8; 3]) -> bool {
    (y0..img.h).any(|y| (0..img.w).any(|x| img.at(x, y) == c))
}

#[test]
fn flicker_png_colours_pixels_by_flip_rate_on_one_scale() {
    let a = flips(&[
        Some(0.0),
        Some(0.5),
        Some(1.0),
        None,
        None,
        Some(0.0),
        Some(0.5),
        Some(1.0),
    ]);
    let b = flips(&[Some(0.0); 8]);
    let png = flicker_png(&[Panel::snapped(&a), Panel::unsnapped(&b)]).unwrap();
    if let Ok(dir) = std::env::var("CSM_LAB_PICTURES_OUT") {
        std::fs::write(format!("{dir}/flicker.png"), &png).unwrap();
    }
    let img = decode(&png);
    // 632 / 4 = 158, 900 / 2 = 450: k = 158.
    let (k, pw) = (158, 632);
    assert_eq!(img.w, 2 * pw + GAP);
    let want = |v: Option<f64>| match v {
        None => colours::EMPTY,
        Some(0.0) => LOW,
        Some(0.5) => MID,
        Some(_) => HIGH,
    };
    for (i, im) in [&a, &b].into_iter().enumerate() {
        for k_ in 0..8u32 {
            let (x, y) = centre(i as u32, pw, k, k_ % 4, k_ / 4);
            assert_eq!(img.at(x, y), want(im.flips[k_ as usize]), "panel {i} pixel {k_}");
        }
    }
    // The colour bar: 90 steps of 4 pixels from x = 10, 8..22 pixels into the legend, each the
    // colour of its step's middle: step 0 at t = 1/180, step 89 at t = 179/180 (interpolated
    // between the stops here).
    let bar_y = TITLE_H + 2 * k + 15;
    assert_eq!(img.at(12, bar_y), BAR_FIRST);
    assert_eq!(img.at(10 + 4 * 89 + 2, bar_y), BAR_LAST);
    // With a largest rate of 0.3 the scale ends at 0.3 (a tick): 0.3 is the top colour.
    assert_eq!(flip_scale_max(0.3), 0.3);
    assert_eq!(flip_scale_max(0.27), 0.3);
    assert_eq!(flip_scale_max(1.0), 1.0);
    assert_eq!(flip_scale_max(0.0), 0.0);
    let c = flips(&[Some(0.3), Some(0.15), Some(0.0), None, None, None, None, None]);
    let one = decode(&flicker_png(&[Panel::snapped(&c)]).unwrap());
    // One panel: 1280 / 4 = 320, 900 / 2 = 450: k = 320.
    assert_eq!(one.at(160, TITLE_H + 160), HIGH);
    assert_eq!(one.at(320 + 160, TITLE_H + 160), MID);
    assert_eq!(one.at(640 + 160, TITLE_H + 160), LOW);
}

#[test]
fn flicker_png_with_nothing_to_show_draws_no_colour_bar() {
    // The bar's top colour is in the legend when something flipped, and absent when nothing did
    // (the legend then says so in words) or there is no receiver at all.
    let some = flips(&[Some(1.0), Some(0.0), None, None, None, None, None, None]);
    let still = flips(&[Some(0.0), Some(0.0), None, None, None, None, None, None]);
    let none = flips(&[None; 8]);
    let panel_end = TITLE_H + 2 * 320;
    let img = decode(&flicker_png(&[Panel::snapped(&some)]).unwrap());
    assert!(has_colour_below(&img, panel_end, BAR_LAST));
    assert_eq!(img.at(12, panel_end + 15), BAR_FIRST);
    for im in [&still, &none] {
        let img = decode(&flicker_png(&[Panel::snapped(im)]).unwrap());
        assert_eq!(img.w, 1280);
        for c in [HIGH, MID, BAR_FIRST, BAR_LAST] {
            assert!(!has_colour_below(&img, panel_end, c));
        }
    }
    let e = flicker_png(&[Panel::snapped(&flips(&[Some(f64::NAN); 8]))])
        .unwrap_err()
        .to_string();
    assert!(e.contains("flip rate NaN") && e.contains("[0, 1]"), "{e}");
}

/// A deterministic pseudo-random state per (frame, pixel): the least compressible content.
fn noise(cols: u32, rows: u32, frame: usize, salt: u64) -> ShadeImage {
    let mut im = ShadeImage::empty(cols, rows);
    let mut x = (frame as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ salt;
    for p in im.pixels.iter_mut() {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        *p = SHADES[(x % 6) as usize];
    }
    im
}

struct Decoded {
    width: u32,
    height: u32,
    num_frames: u32,
    plays: u32,
    /// (delay_num, delay_den) of each frame.
    delays: Vec<(u16, u16)>,
    first: Vec<u8>,
    last: Vec<u8>,
}

fn decode_animation(bytes: &[u8]) -> Decoded {
    let mut r = decoder(bytes);
    let actl = r.info().animation_control.expect("an APNG");
    let (width, height) = (r.info().width, r.info().height);
    let mut buf = vec![0; r.output_buffer_size()];
    let mut delays = Vec::new();
    let mut first = Vec::new();
    for i in 0..actl.num_frames {
        r.next_frame(&mut buf).unwrap();
        let fc = r.info().frame_control.expect("a frame control");
        assert_eq!((fc.width, fc.height, fc.x_offset, fc.y_offset), (width, height, 0, 0));
        delays.push((fc.delay_num, fc.delay_den));
        if i == 0 {
            first = buf.clone();
        }
    }
    let last = buf.clone();
    assert!(r.next_frame(&mut buf).is_err(), "no frame past num_frames");
    Decoded {
        width,
        height,
        num_frames: actl.num_frames,
        plays: actl.num_plays,
        delays,
        first,
        last,
    }
}

#[test]
fn the_animation_shows_every_kth_frame_at_its_delay() {
    // The default grid over a 240-frame path: 48 frames, every 5th, held 5/30 s.
    let plan = AnimationPlan::new(240, 240, 135, &["snapped", "unsnapped"], &ANIMATION_CAPS).unwrap();
    assert_eq!((plan.every, plan.shown, plan.delay_ms), (5, 48, 167));
    assert_eq!(plan.frames().take(3).collect::<Vec<_>>(), [0, 5, 10]);
    let mut asked = Vec::new();
    let frames = (0..240).map(|f| {
        asked.push(f);
        vec![noise(240, 135, f, 1), noise(240, 135, f, 2)]
    });
    let mut bytes = Vec::new();
    let n = write_animation(&plan, frames, &mut bytes).unwrap();
    if let Ok(dir) = std::env::var("CSM_LAB_PICTURES_OUT") {
        std::fs::write(format!("{dir}/shadow_noise.apng"), &bytes).unwrap();
    }
    assert_eq!(n, bytes.len() as u64);
    let d = decode_animation(&bytes);
    assert_eq!(d.num_frames, 48);
    assert_eq!(d.plays, 0, "loops forever");
    assert!(d.delays.iter().all(|x| *x == (167, 1000)), "{:?}", &d.delays[..3]);
    // Panels side by side: 2 × 480 + 16 wide (k = 2 within 1000 × 540).
    assert_eq!(d.width, 976);
    assert!(d.width <= ANIMATION_CAPS.max_width && d.height <= ANIMATION_CAPS.max_height);
    // The first frame shows path frame 0: panel pixels in their states' colours.
    let first = Rgb {
        w: d.width,
        h: d.height,
        px: d.first,
    };
    let (a, b) = (noise(240, 135, 0, 1), noise(240, 135, 0, 2));
    let y0 = TITLE_H + 6;
    for (c, r) in [(0, 0), (17, 3), (239, 134), (100, 60)] {
        assert_eq!(first.at(c * 2 + 1, y0 + r * 2 + 1), state_rgb(a.get(c, r)));
        assert_eq!(first.at(496 + c * 2 + 1, y0 + r * 2 + 1), state_rgb(b.get(c, r)));
    }
    // The progress bar: frame 1 of 240 fills 976 / 240 = 4 pixels.
    assert_eq!(first.at(1, TITLE_H + 2), colours::PROGRESS);
    assert_ne!(first.at(10, TITLE_H + 2), colours::PROGRESS);
    assert!(bytes.len() as u64 <= plan.byte_bound());
    // Same frames, same bytes.
    let mut again = Vec::new();
    let frames = (0..240).map(|f| vec![noise(240, 135, f, 1), noise(240, 135, f, 2)]);
    write_animation(&plan, frames, &mut again).unwrap();
    assert_eq!(bytes, again);
}

#[test]
fn a_long_path_stays_under_the_caps() {
    // 10 000 frames of noise on a grid larger than the animation (shrunk to fit): at most 48
    // frames, and the file under its bound and under 16 MiB.
    let (cols, rows) = (1200, 700);
    let plan = AnimationPlan::new(10_000, cols, rows, &["snapped", "unsnapped"], &ANIMATION_CAPS).unwrap();
    assert!(plan.shown <= 48);
    assert_eq!(plan.every, 10_000usize.div_ceil(plan.shown.max(1)).max(plan.every));
    assert_eq!(plan.shown, 10_000usize.div_ceil(plan.every));
    assert_eq!(plan.delay_ms, 500, "clamped to half a second");
    assert!(plan.byte_bound() <= ANIMATION_CAPS.max_bytes);
    let every = plan.every;
    let blank = ShadeImage::empty(cols, rows);
    // Only the shown frames are noise (the others are skipped unseen).
    let frames = (0..10_000).map(|f| {
        if f % every == 0 {
            vec![noise(cols, rows, f, 3), noise(cols, rows, f, 4)]
        } else {
            vec![blank.clone(), blank.clone()]
        }
    });
    let mut bytes = Vec::new();
    write_animation(&plan, frames, &mut bytes).unwrap();
    let d = decode_animation(&bytes);
    assert_eq!(d.num_frames as usize, plan.shown);
    assert!(d.width <= 1000 && d.height <= 540);
    assert!(d.delays.iter().all(|x| *x == (500, 1000)));
    assert!(
        (bytes.len() as u64) <= plan.byte_bound() && (bytes.len() as u64) <= ANIMATION_CAPS.max_bytes,
        "{} bytes, bound {}",
        bytes.len(),
        plan.byte_bound()
    );
}

#[test]
fn a_short_path_is_an_error_not_a_broken_file() {
    let plan = AnimationPlan::new(20, 8, 4, &["snapped"], &ANIMATION_CAPS).unwrap();
    assert_eq!((plan.every, plan.shown), (1, 20));
    let e = write_animation(&plan, (0..10).map(|_| vec![synthetic(0)]), &mut Vec::new())
        .unwrap_err()
        .to_string();
    assert!(e.contains("gave 10 of the 20 frames"), "{e}");
    let e = write_animation(
        &plan,
        (0..20).map(|_| vec![synthetic(0), synthetic(1)]),
        &mut Vec::new(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("2 images for 1 panels"), "{e}");
    assert!(AnimationPlan::new(0, 8, 4, &["snapped"], &ANIMATION_CAPS).is_err());
}

/// Slope, intercept and Pearson's r from raw sums (n Σxy - Σx Σy form).
fn raw_fit(x: &[f64], y: &[f64]) -> (f64, f64, f64) {
    let n = x.len() as f64;
    let (sx, sy): (f64, f64) = (x.iter().sum(), y.iter().sum());
    let sxx: f64 = x.iter().map(|v| v * v).sum();
    let syy: f64 = y.iter().map(|v| v * v).sum();
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| a * b).sum();
    let b = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    let a = (sy - b * sx) / n;
    let r = (n * sxy - sx * sy) / ((n * sxx - sx * sx) * (n * syy - sy * sy)).sqrt();
    (a, b, r)
}

/// Spearman's ρ without ties: 1 - 6 Σd² / (n (n² - 1)), ranks by counting.
fn raw_spearman(x: &[f64], y: &[f64]) -> f64 {
    let rank = |v: &[f64], i: usize| v.iter().filter(|w| **w < v[i]).count() as f64;
    let n = x.len() as f64;
    let d2: f64 = (0..x.len()).map(|i| (rank(x, i) - rank(y, i)).powi(2)).sum();
    1.0 - 6.0 * d2 / (n * (n * n - 1.0))
}

fn sample_points() -> Vec<ShimmerPoint> {
    (0..12)
        .map(|i| {
            let t = i as f64;
            let snapped = i % 3 == 0;
            ShimmerPoint {
                s3: 0.01 * t + 0.002 * (t * 1.7).sin(),
                s4: 0.006 * t * t + 0.01 * (t * 0.9).cos().abs(),
                s5: if snapped {
                    0.0
                } else {
                    0.004 * t + 0.001 * (t * 2.3).sin()
                },
                snapped,
            }
        })
        .collect()
}

#[test]
fn the_scatter_fit_equals_an_independent_computation() {
    let pts = sample_points();
    let fig = FlickerVsShimmer {
        name: "default",
        points: &pts,
    };
    let (f3, f4) = fig.fits();
    let s5: Vec<f64> = pts.iter().map(|p| p.s5).collect();
    for (f, x) in [
        (f3, pts.iter().map(|p| p.s3).collect::<Vec<_>>()),
        (f4, pts.iter().map(|p| p.s4).collect()),
    ] {
        let (a, b, r) = raw_fit(&x, &s5);
        let (fa, fb) = f.line.unwrap();
        assert!((fa - a).abs() <= 1e-12 + 1e-9 * a.abs(), "{fa} vs {a}");
        assert!((fb - b).abs() <= 1e-9 * b.abs(), "{fb} vs {b}");
        assert!((f.pearson.unwrap() - r).abs() <= 1e-9, "{:?} vs {r}", f.pearson);
        assert_eq!(f.n, 12);
        let rho = f.spearman.unwrap();
        // s5 has ties (the snapped zeros): compare with Pearson of averaged ranks computed here.
        let mut order: Vec<usize> = (0..12).collect();
        order.sort_by(|&i, &j| s5[i].total_cmp(&s5[j]));
        let zeros = s5.iter().filter(|v| **v == 0.0).count() as f64;
        let ry: Vec<f64> = s5
            .iter()
            .map(|v| {
                if *v == 0.0 {
                    (zeros + 1.0) / 2.0
                } else {
                    s5.iter().filter(|w| **w < *v).count() as f64 + 1.0
                }
            })
            .collect();
        let rx: Vec<f64> = x
            .iter()
            .map(|v| x.iter().filter(|w| **w < *v).count() as f64 + 1.0)
            .collect();
        let (_, _, want) = raw_fit(&rx, &ry);
        assert!((rho - want).abs() <= 1e-12, "{rho} vs {want}");
    }
    // The numbers are printed in the figure, and nothing non-finite is.
    let svg = String::from_utf8(fig.to_svg().unwrap()).unwrap();
    let (a, b) = f3.line.unwrap();
    let line = format!(
        "S5 = {} + {} · S3",
        csm_lab::output::short_number(a),
        csm_lab::output::short_number(b)
    );
    assert!(svg.contains(&line), "{line} not in the figure");
    assert!(svg.contains(&format!("Pearson r = {:.3}", f3.pearson.unwrap())));
    assert!(svg.contains("Spearman ρ ="));
    for bad in ["NaN", "inf"] {
        assert!(!svg.contains(bad), "{bad} in the SVG");
    }
    assert_eq!(svg.as_bytes(), &fig.to_svg().unwrap()[..]);
    // The house check of every command's figures: data marks drawn, no legend over one.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("flicker_vs_shimmer.svg");
    std::fs::write(&path, &svg).unwrap();
    assert_eq!(crate::figures::problems(&path), Vec::<String>::new());
    let png = fig.to_png().unwrap();
    assert_eq!(png, fig.to_png().unwrap());
    if let Ok(dir) = std::env::var("CSM_LAB_PICTURES_OUT") {
        std::fs::write(format!("{dir}/flicker_vs_shimmer.png"), &png).unwrap();
    }
}

#[test]
fn spearman_without_ties_matches_the_rank_difference_formula() {
    let x = [0.3, 0.1, 0.7, 0.2, 0.9, 0.5];
    let y = [2.0, 1.5, 0.1, 3.0, 4.0, 2.5];
    let f = fit(&x, &y);
    assert!((f.spearman.unwrap() - raw_spearman(&x, &y)).abs() < 1e-12);
    assert_eq!(ranks(&[1.0, 2.0, 2.0, 3.0]), [1.0, 2.5, 2.5, 4.0]);
}

#[test]
fn a_constant_flicker_has_no_correlation_and_no_nan() {
    // Snapped sphere fits only: S5 is 0 everywhere; the line is flat, r undefined and said so.
    let pts: Vec<ShimmerPoint> = (0..5)
        .map(|i| ShimmerPoint {
            s3: i as f64 * 0.01,
            s4: i as f64 * 0.1,
            s5: 0.0,
            snapped: true,
        })
        .collect();
    let fig = FlickerVsShimmer {
        name: "snapped",
        points: &pts,
    };
    let (f3, _) = fig.fits();
    assert_eq!(f3.line, Some((0.0, 0.0)));
    assert_eq!(f3.pearson, None);
    let svg = String::from_utf8(fig.to_svg().unwrap()).unwrap();
    assert!(svg.contains("undefined (a constant)"));
    assert!(!svg.contains("NaN") && !svg.contains("inf"));
    // No point at all: the figure says so.
    let empty = FlickerVsShimmer {
        name: "none",
        points: &[],
    };
    let svg = String::from_utf8(empty.to_svg().unwrap()).unwrap();
    assert!(svg.contains("No configuration with a measured flicker S5."));
    // The sweep's figure tuple.
    let (stem, caption, bytes) = truth::flicker_vs_shimmer_figure("d", &pts).unwrap();
    assert_eq!(stem, "flicker_vs_shimmer");
    assert!(caption.contains("S5") && bytes.starts_with(b"<svg"));
}

#[test]
fn the_report_section_embeds_the_pictures_with_captions() {
    let (a, b) = (synthetic(0), synthetic(1));
    let shadow = shadow_png(&[Panel::snapped(&a), Panel::unsnapped(&b)]).unwrap();
    let fl = flips(&[
        Some(0.0),
        Some(0.5),
        Some(1.0),
        None,
        None,
        Some(0.0),
        Some(0.5),
        Some(1.0),
    ]);
    let flicker = flicker_png(&[Panel::snapped(&fl)]).unwrap();
    let plan = AnimationPlan::new(10, 8, 4, &["snapped", "unsnapped"], &ANIMATION_CAPS).unwrap();
    let mut apng = Vec::new();
    write_animation(&plan, (0..10).map(|f| vec![synthetic(f), synthetic(f + 1)]), &mut apng).unwrap();
    let pictures = TruthPictures {
        shadow_png: Some(shadow.clone()),
        flicker_png: Some(flicker.clone()),
        animation: Some(Animation::Bytes(apng.clone())),
    };
    let body = section("recommended", &pictures);
    let page = String::from_utf8(csm_lab::report::html::page("t", "h", &body, "")).unwrap();
    let doc = roxmltree::Document::parse_with_options(
        &page,
        roxmltree::ParsingOptions {
            allow_dtd: true,
            ..Default::default()
        },
    )
    .unwrap();
    let imgs: Vec<(String, String)> = doc
        .descendants()
        .filter(|n| n.has_tag_name("img"))
        .map(|n| {
            (
                n.attribute("src").unwrap().to_string(),
                n.attribute("alt").unwrap().to_string(),
            )
        })
        .collect();
    assert_eq!(imgs.len(), 3);
    let payload = |src: &str, kind: &str| unbase64(src.strip_prefix(&format!("data:image/{kind};base64,")).unwrap());
    assert_eq!(payload(&imgs[0].0, "png"), shadow);
    assert_eq!(payload(&imgs[1].0, "png"), flicker);
    assert_eq!(payload(&imgs[2].0, "apng"), apng);
    assert!(imgs[0].1.contains("acne (magenta)") && imgs[0].1.contains("leaks (cyan)"));
    assert!(imgs[1].1.contains("flipped"));
    assert!(imgs[2].1.contains("shadow.apng"));
    let captions = doc.descendants().filter(|n| n.has_tag_name("figcaption")).count();
    assert_eq!(captions, 3);
}

#[test]
fn the_animation_streams_into_an_output_set() {
    // Through the output layer's all-or-nothing set: the same bytes as written directly, the
    // path started over by the file itself.
    let plan = AnimationPlan::new(30, 8, 4, &["snapped", "unsnapped"], &ANIMATION_CAPS).unwrap();
    let frames = || (0..30).map(|f| vec![synthetic(f), synthetic(f + 3)]);
    let mut direct = Vec::new();
    write_animation(&plan, frames(), &mut direct).unwrap();
    let file = truth::ShadowAnimation { plan, frames };
    let dir = tempfile::tempdir().unwrap();
    let other = vec![("shadow.png".to_string(), vec![1u8, 2, 3])];
    let written = csm_lab::output::write_files_streamed(dir.path(), &other, &[&file]).unwrap();
    assert_eq!(written.len(), 2);
    assert_eq!(std::fs::read(dir.path().join("shadow.apng")).unwrap(), direct);
    assert_eq!(decode_animation(&direct).num_frames, 30);
}
