//! Option values every command parses alike, checked by clap so that a bad one is a usage error
//! (exit 2) naming the option, the same in every command.

use terrain_engine::scene::Mode;

/// The largest image side any command renders (camera.width's range).
pub const MAX_SIDE: u32 = 16384;

/// `--size`: `N` (square) or `WxH`, each 1 to [`MAX_SIDE`] pixels, the same for every command.
pub fn size(s: &str) -> Result<(u32, u32), String> {
    let side =
        |v: &str| -> Option<u32> { v.trim().parse().ok().filter(|n| (1..=MAX_SIDE).contains(n)) };
    let size = match s.split_once(['x', 'X', '×']) {
        Some((w, h)) => side(w).zip(side(h)),
        None => side(s).map(|n| (n, n)),
    };
    size.ok_or_else(|| format!("expected N or WxH, each 1 to {MAX_SIDE} pixels"))
}

/// `--fps`, `--path-fps`: frames per second in (0, 1000].
pub fn fps(s: &str) -> Result<f64, String> {
    s.trim()
        .parse::<f64>()
        .ok()
        .filter(|f| f.is_finite() && *f > 0.0 && *f <= 1000.0)
        .ok_or_else(|| "expected frames per second in (0, 1000]".into())
}

/// `--tau`: a positive number of pixels.
pub fn positive_px(s: &str) -> Result<f64, String> {
    s.trim()
        .parse::<f64>()
        .ok()
        .filter(|f| f.is_finite() && *f > 0.0)
        .ok_or_else(|| "expected a positive number of pixels".into())
}

/// `--shard I/N` with 0 ≤ I < N.
pub fn shard(s: &str) -> Result<(usize, usize), String> {
    s.split_once('/')
        .and_then(|(i, n)| Some((i.trim().parse().ok()?, n.trim().parse().ok()?)))
        .filter(|&(i, n): &(usize, usize)| n > 0 && i < n)
        .ok_or_else(|| "expected I/N with 0 ≤ I < N".into())
}

/// `view --mode`, `compare --modes`: a mode compare sweeps and the window flies (not the
/// reference), over a sketch or a planet.
pub fn mesh_mode(s: &str) -> Result<Mode, String> {
    one_of(&Mode::compared().collect::<Vec<_>>(), s)
}

fn one_of(modes: &[Mode], s: &str) -> Result<Mode, String> {
    modes
        .iter()
        .copied()
        .find(|m| m.name() == s)
        .ok_or_else(|| {
            let names: Vec<&str> = modes.iter().map(|m| m.name()).collect();
            format!("expected one of {}", names.join(", "))
        })
}

/// A value of a named enum (a mode, a view, a warp method) by its name: the names are the
/// possible values `--help` lists and a bad value's error names.
pub fn named<T: terrain_engine::Named>() -> impl clap::builder::TypedValueParser<Value = T> {
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(T::all().iter().map(|v| v.name())).try_map(
        |s: String| {
            T::all()
                .iter()
                .copied()
                .find(|v| v.name() == s)
                .ok_or_else(|| format!("unknown value {s:?}"))
        },
    )
}

/// `--outputs rgb,depth,…`: the ground truth written beside each image (docs/batch.md).
pub fn outputs(s: &str) -> Result<Vec<terrain_engine::truth::Output>, String> {
    terrain_engine::truth::parse_outputs(s)
}
