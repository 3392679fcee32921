//! `terrain web SCENE --out-dir SITE [--serve]`: the scene as a static web site, drawn in the
//! browser by the same renderer through WebGPU (the `terrain-web` crate, compiled to
//! WebAssembly), and served on 127.0.0.1 for a look.
//!
//! The site: `index.html` and `main.js` (the page), `pkg/` (the module and its glue, as
//! `wasm-bindgen --target web` writes them), `scene.toml` (the scene as resolved, `--set`s,
//! `--size` and `--mode` applied, its sketch named relative to the site), `sketch/` (the sketch
//! file) and `site.json` (what the page loads). Every file is written atomically.
//!
//! The module comes from `--pkg DIR`, or is built from the workspace this binary was built in
//! (`cargo build --release --target wasm32-unknown-unknown -p terrain-web`, then `wasm-bindgen`;
//! cargo rebuilds only what changed). Rejected: a module embedded in the binary, which would
//! need the wasm build inside every native build.

mod serve;

use crate::args;
use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};
use std::process::Command;
use terrain_cli::output::write_atomic;
use terrain_engine::scene::{self, Mode, Scene};
use terrain_engine::{Error, Role};

#[derive(clap::Args)]
pub struct Args {
    /// A scene file (.toml), or a sketch (height map) to show with every default.
    scene: PathBuf,
    /// The folder the site is written into (created; the site's files are replaced, others
    /// left alone).
    #[arg(long)]
    out_dir: PathBuf,
    /// Serves the site on 127.0.0.1 after writing it, until interrupted; prints its address.
    #[arg(long)]
    serve: bool,
    /// The port `--serve` listens on (0: any free one).
    #[arg(long, default_value_t = 8000)]
    port: u16,
    /// The scene camera's image size: N (square) or WxH; the page's size with `?still=1`.
    #[arg(long, value_name = "N|WxH", value_parser = args::size)]
    size: Option<(u32, u32)>,
    /// The mode the page starts in [default: the scene's; warped for the reference].
    #[arg(long, value_parser = args::mesh_mode)]
    mode: Option<Mode>,
    /// Overrides a scene key (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// A module already built (`terrain_web.js` and `terrain_web_bg.wasm`), instead of
    /// building it from the workspace.
    #[arg(long, value_name = "DIR")]
    pkg: Option<PathBuf>,
}

/// The page, from the web crate.
const INDEX_HTML: &str = include_str!("../../../crates/terrain-web/site/index.html");
const MAIN_JS: &str = include_str!("../../../crates/terrain-web/site/main.js");
/// The module's files, as `wasm-bindgen --target web` names them.
const PKG_FILES: [&str; 2] = ["terrain_web.js", "terrain_web_bg.wasm"];
/// The workspace this binary was built in: where the module is built from.
const WORKSPACE: &str = env!("CARGO_MANIFEST_DIR");

pub fn run(a: Args) -> Result<()> {
    let mut scene = crate::load_scene(&a.scene, &a.set)?;
    if let Some((w, h)) = a.size {
        (scene.camera.width, scene.camera.height) = (w, h);
    }
    let sketch = sketch_file(&scene)?;
    // The sketch read here first: a file the page could not read fails now, in one line.
    let atlas = scene::load_atlas(&scene)?;
    crate::warn(&scene::warnings(&scene, &atlas));
    scene::camera_of(&scene, &atlas)?;
    let mode = match a.mode {
        Some(m) => m,
        None if scene.render.mode == Mode::Reference => Mode::Warped,
        None => scene.render.mode,
    };
    let pkg = match &a.pkg {
        Some(dir) => dir.clone(),
        None => build_module()?,
    };
    write_site(&a.out_dir, &scene, sketch.as_deref(), mode, &pkg)?;
    eprintln!(
        "{}: the site of {} ({} × {}, {mode})",
        a.out_dir.display(),
        a.scene.display(),
        scene.camera.width,
        scene.camera.height
    );
    if a.serve {
        serve::run(&a.out_dir, a.port)?;
    }
    Ok(())
}

/// The sketch's one file, where the scene has one (a synthetic sketch has none). What the page
/// cannot fetch as one file is refused, naming the key.
fn sketch_file(scene: &Scene) -> Result<Option<PathBuf>> {
    let refuse = |key: &'static str, why: &str| -> Result<Option<PathBuf>> {
        Err(Error::value(key, format!("{why}: the web page does not carry it")).into())
    };
    if scene.planet().is_some() {
        return refuse(
            "planet",
            "a planet is drawn in clipmaps from a global sketch",
        );
    }
    if scene.surface.image.is_some() {
        return refuse("surface.image", "draped imagery is read from disk");
    }
    if scene.surface.color_ramp.is_some() {
        return refuse("surface.color_ramp", "a colour ramp is read from disk");
    }
    if scene.importance.max_map.is_some() {
        return refuse("importance.max_map", "an importance map is read from disk");
    }
    let Some(p) = &scene.sketch.path else {
        return Ok(None);
    };
    let path = scene.resolve(p);
    let text = path.to_string_lossy();
    let mosaic = text.contains(['*', '?', '['])
        || path.is_dir()
        || path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("vrt"))
        || path.file_name() == Some(std::ffi::OsStr::new("pyramid.toml"));
    if mosaic {
        let why = "a mosaic, a .vrt or a tile pyramid: the web page reads one sketch file \
                   (`terrain tiles` cannot flatten it; give one GeoTIFF, .asc or .hgt)";
        return Err(Error::file(Role::Sketch, &path, why).into());
    }
    Ok(Some(path))
}

/// Writes the site into `out`: the page, the module from `pkg`, the scene, its sketch and
/// `site.json`.
fn write_site(
    out: &Path,
    scene: &Scene,
    sketch: Option<&Path>,
    mode: Mode,
    pkg: &Path,
) -> Result<()> {
    std::fs::create_dir_all(out.join("pkg")).map_err(|e| Error::io(Role::OutputFolder, out, e))?;
    write_atomic(&out.join("index.html"), INDEX_HTML.as_bytes())?;
    write_atomic(&out.join("main.js"), MAIN_JS.as_bytes())?;
    for name in PKG_FILES {
        let from = pkg.join(name);
        let bytes = std::fs::read(&from).map_err(|e| {
            Error::io(Role::Output, &from, e).to_string()
                + " (the web module: build it, or give --pkg the folder wasm-bindgen wrote)"
        });
        write_atomic(
            &out.join("pkg").join(name),
            &bytes.map_err(anyhow::Error::msg)?,
        )?;
    }
    let mut site_scene = scene.clone();
    let sketch_url = match sketch {
        Some(path) => {
            let name = path.file_name().context("the sketch has no file name")?;
            let url = Path::new("sketch").join(name);
            let bytes = std::fs::read(path).map_err(|e| Error::io(Role::Sketch, path, e))?;
            std::fs::create_dir_all(out.join("sketch"))
                .map_err(|e| Error::io(Role::OutputFolder, out, e))?;
            write_atomic(&out.join(&url), &bytes)?;
            site_scene.sketch.path = Some(url.clone());
            Some(url.to_string_lossy().replace('\\', "/"))
        }
        None => None,
    };
    let text = toml::to_string(&site_scene).map_err(|e| Error::encode("the site's scene", e))?;
    write_atomic(&out.join("scene.toml"), text.as_bytes())?;
    let site = serde_json::json!({
        "scene": "scene.toml",
        "sketch": sketch_url,
        "mode": mode.name(),
        "width": scene.camera.width,
        "height": scene.camera.height,
    });
    write_atomic(&out.join("site.json"), site.to_string().as_bytes())?;
    Ok(())
}

/// Builds the module from the workspace this binary was built in; returns the folder of its
/// files. Each tool it needs, where missing, is named with the command that installs it.
fn build_module() -> Result<PathBuf> {
    let workspace = Path::new(WORKSPACE);
    if !workspace.join("crates/terrain-web/Cargo.toml").is_file() {
        bail!(
            "the web module: this terrain was built outside its workspace ({WORKSPACE} is gone); \
             give --pkg the folder `wasm-bindgen --target web` wrote"
        );
    }
    // A target folder of its own: the build may run while `cargo test` holds the workspace's.
    let target = workspace.join("target/web");
    eprintln!(
        "building the web module (cargo build --release --target wasm32-unknown-unknown -p terrain-web, SIMD)"
    );
    let status = Command::new(std::env::var_os("CARGO").unwrap_or("cargo".into()))
        .current_dir(workspace)
        .env("CARGO_TARGET_DIR", &target)
        // WebAssembly SIMD (every current browser runs it): the CPU stage in the page takes
        // about half the time (docs/decisions.md, "The web page").
        .env(
            "CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_RUSTFLAGS",
            "-C target-feature=+simd128",
        )
        .args(["build", "--release", "--target", "wasm32-unknown-unknown"])
        .args(["-p", "terrain-web", "--quiet"])
        .status()
        .context("the web module: cannot run cargo")?;
    if !status.success() {
        bail!(
            "the web module did not build (cargo said why above; a missing target is added by \
             `rustup target add wasm32-unknown-unknown`)"
        );
    }
    let wasm = target.join("wasm32-unknown-unknown/release/terrain_web.wasm");
    let pkg = target.join("pkg");
    let version = wasm_bindgen_version(workspace)?;
    let bindgen = Command::new("wasm-bindgen").arg("--version").output();
    let have = match bindgen {
        Ok(o) if o.status.success() => String::from_utf8_lossy(&o.stdout).trim().to_string(),
        _ => bail!(
            "the web module: wasm-bindgen is not installed (cargo install wasm-bindgen-cli \
             --version {version})"
        ),
    };
    if !have.ends_with(&version) {
        bail!(
            "the web module: {have} is installed, the workspace pins {version} (cargo install \
             wasm-bindgen-cli --version {version} --force)"
        );
    }
    let status = Command::new("wasm-bindgen")
        .args(["--target", "web", "--no-typescript", "--out-dir"])
        .arg(&pkg)
        .arg(&wasm)
        .status()
        .context("the web module: cannot run wasm-bindgen")?;
    if !status.success() {
        bail!("the web module: wasm-bindgen failed on {}", wasm.display());
    }
    Ok(pkg)
}

/// The wasm-bindgen version the workspace's lockfile pins (the glue's generator must match).
fn wasm_bindgen_version(workspace: &Path) -> Result<String> {
    let lock = workspace.join("Cargo.lock");
    let text = std::fs::read_to_string(&lock).with_context(|| lock.display().to_string())?;
    let mut lines = text.lines();
    while let Some(line) = lines.next() {
        if line == "name = \"wasm-bindgen\"" {
            let v = lines.next().and_then(|l| l.strip_prefix("version = \""));
            if let Some(v) = v.and_then(|v| v.strip_suffix('"')) {
                return Ok(v.to_string());
            }
        }
    }
    bail!("{}: no wasm-bindgen in the lockfile", lock.display())
}
