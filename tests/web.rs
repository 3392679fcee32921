//! `terrain web` in a real browser: the site of the bundled scene and of a user's GeoTIFF,
//! served on 127.0.0.1 by `--serve`, opened in headless Chromium with WebGPU on SwiftShader
//! (driven over the DevTools protocol), shows with `?still=1` what `terrain render` draws for the
//! same camera and size (PSNR ≥ 30 dB: two rasterisers, one terrain); flown along its path for
//! sixty frames and switched to the wireframe, it logs no console error; a browser
//! without WebGPU gets the page's message.
//!
//! Own harness (libtest-mimic), one browser at a time. Without Chromium, the wasm32 target or
//! wasm-bindgen the tests report themselves skipped, naming what is missing, and fail where
//! `TERRAIN_REQUIRE_WEB_TESTS` is set (`.ci/run` installs them and sets it). SwiftShader draws on
//! the machine's CPU, seconds a frame: the stills are the issue's 512², the flight a 128² viewport.

mod common;
use common::*;
use headless_chrome::protocol::cdp::{Emulation, Page, Runtime};
use headless_chrome::{Browser, LaunchOptions, Tab};
use libtest_mimic::Arguments;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use terrain_cli::eval::metrics::psnr;

/// The still's size: the issue's 512².
const SIZE: u32 = 512;
/// The flight's viewport, CSS pixels square (the canvas fills it): SwiftShader draws a 512²
/// frame of the bundled scene in about 24 s on two cores, this one in about a second.
const FLIGHT_VIEWPORT: u32 = 128;

fn main() {
    let mut args = Arguments::from_args();
    // One browser at a time: each page renders on SwiftShader, on the machine's CPU cores.
    args.test_threads = Some(1);
    let tests: [(&'static str, fn()); 3] = [
        (
            "the_page_draws_what_render_draws_for_the_bundled_scene_and_a_users_geotiff",
            the_page_draws_what_render_draws_for_the_bundled_scene_and_a_users_geotiff,
        ),
        (
            "the_page_flies_its_path_and_switches_mode_and_view_without_a_console_error",
            the_page_flies_its_path_and_switches_mode_and_view_without_a_console_error,
        ),
        (
            "a_browser_without_webgpu_gets_a_message_not_a_blank_page",
            a_browser_without_webgpu_gets_a_message_not_a_blank_page,
        ),
    ];
    let frames = (missing(), "TERRAIN_REQUIRE_WEB_TESTS");
    // The message needs the browser alone (the page says it before it loads the module).
    let browser_only = (
        chromium()
            .is_none()
            .then(|| "Chromium not installed (Debian: apt-get install chromium)".to_string()),
        "TERRAIN_REQUIRE_WEB_TESTS",
    );
    let trials = tests
        .into_iter()
        .map(|(name, test)| {
            let (why_not, required) = match name.starts_with("a_browser_without_webgpu") {
                true => browser_only.clone(),
                false => frames.clone(),
            };
            skippable_trial(name, test, why_not, required)
        })
        .collect();
    libtest_mimic::run(&args, trials).exit();
}

/// Why the page cannot be tested here, if it cannot.
fn missing() -> Option<String> {
    let mut absent = Vec::new();
    if chromium().is_none() {
        absent.push("Chromium (Debian: apt-get install chromium)");
    }
    let ok = |program: &str, args: &[&str]| {
        Command::new(program)
            .args(args)
            .output()
            .is_ok_and(|o| o.status.success())
    };
    if !ok("wasm-bindgen", &["--version"]) {
        absent.push("wasm-bindgen (cargo install wasm-bindgen-cli --version <the lockfile's>)");
    }
    let targets = Command::new("rustup")
        .args(["target", "list", "--installed"])
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).into_owned())
        .unwrap_or_default();
    if !targets.lines().any(|t| t == "wasm32-unknown-unknown") {
        absent.push("the wasm32-unknown-unknown target (rustup target add wasm32-unknown-unknown)");
    }
    (!absent.is_empty()).then(|| format!("{} not installed", absent.join(", ")))
}

fn chromium() -> Option<PathBuf> {
    ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .filter_map(|name| {
            let out = Command::new("sh")
                .args(["-c", &format!("command -v {name}")])
                .output()
                .ok()?;
            let path = String::from_utf8_lossy(&out.stdout).trim().to_string();
            (out.status.success() && !path.is_empty()).then(|| PathBuf::from(path))
        })
        .next()
}

/// `terrain web SOURCE --out-dir DIR --size 512 --serve --port 0` running; its address.
struct Site {
    server: Child,
    url: String,
}

impl Drop for Site {
    fn drop(&mut self) {
        let _ = self.server.kill();
        let _ = self.server.wait();
    }
}

fn serve(source: &Path, dir: &Path, extra: &[&str]) -> Site {
    let mut server = Command::new(env!("CARGO_BIN_EXE_terrain"))
        .arg("web")
        .arg(source)
        .arg("--out-dir")
        .arg(dir)
        .args(["--size", &SIZE.to_string(), "--serve", "--port", "0"])
        .args(extra)
        .env("TERRAIN_QUIET", "1")
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("run terrain web");
    // The first line is the address, once the site is written (the module built first, which
    // the first test may wait minutes for).
    let mut line = String::new();
    BufReader::new(server.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let url = line.trim().to_string();
    if !url.starts_with("http://127.0.0.1:") {
        let status = server.wait().unwrap();
        panic!("terrain web --serve printed {url:?} and ended: {status}");
    }
    Site { server, url }
}

/// Headless Chromium with WebGPU on SwiftShader.
fn browser() -> Browser {
    let options = LaunchOptions::default_builder()
        .path(chromium())
        .headless(true)
        // Root in a container: Chromium's sandbox needs user namespaces it may not have.
        .sandbox(false)
        // `--disable-gpu` would leave the page without WebGPU.
        .enable_gpu(true)
        .window_size(Some((SIZE + 256, SIZE + 256)))
        .idle_browser_timeout(Duration::from_secs(600))
        .ignore_default_args(vec![
            "--enable-features=NetworkService,NetworkServiceInProcess".as_ref(),
        ])
        .args(vec![
            "--enable-unsafe-webgpu".as_ref(),
            "--use-webgpu-adapter=swiftshader".as_ref(),
            "--enable-features=Vulkan".as_ref(),
            // The machine's network is closed: no connections to Google's services.
            "--disable-quic".as_ref(),
            "--disable-component-update".as_ref(),
        ])
        .build()
        .unwrap();
    Browser::new(options).expect("start Chromium")
}

/// Every console error, uncaught exception and error log entry of `tab`, as text.
fn console_errors(tab: &Tab) -> Arc<Mutex<Vec<String>>> {
    use headless_chrome::protocol::cdp::types::Event;
    let errors = Arc::new(Mutex::new(Vec::new()));
    let seen = errors.clone();
    tab.enable_runtime().unwrap();
    tab.enable_log().unwrap();
    tab.add_event_listener(Arc::new(move |event: &Event| {
        let text = match event {
            Event::RuntimeConsoleAPICalled(e)
                if e.params.Type == Runtime::ConsoleAPICalledEventTypeOption::Error =>
            {
                let args: Vec<String> = e
                    .params
                    .args
                    .iter()
                    .map(|a| {
                        a.value
                            .as_ref()
                            .map_or(a.description.clone().unwrap_or_default(), |v| v.to_string())
                    })
                    .collect();
                Some(format!("console.error: {}", args.join(" ")))
            }
            Event::RuntimeExceptionThrown(e) => {
                Some(format!("exception: {}", e.params.exception_details.text))
            }
            Event::LogEntryAdded(e)
                if e.params.entry.level
                    == headless_chrome::protocol::cdp::Log::LogEntryLevel::Error =>
            {
                Some(format!("log: {}", e.params.entry.text))
            }
            _ => None,
        };
        if let Some(t) = text {
            seen.lock().unwrap().push(t);
        }
    }))
    .unwrap();
    errors
}

/// Evaluates `js` (awaiting a Promise) and returns its value as JSON.
fn eval(tab: &Tab, js: &str) -> serde_json::Value {
    let result = tab
        .call_method(Runtime::Evaluate {
            expression: js.to_string(),
            return_by_value: Some(true),
            await_promise: Some(true),
            generate_preview: None,
            silent: None,
            include_command_line_api: None,
            user_gesture: None,
            object_group: None,
            context_id: None,
            throw_on_side_effect: None,
            timeout: None,
            disable_breaks: None,
            repl_mode: None,
            allow_unsafe_eval_blocked_by_csp: None,
            unique_context_id: None,
            serialization_options: None,
        })
        .unwrap_or_else(|e| panic!("evaluate {js}: {e}"));
    if let Some(details) = result.exception_details {
        panic!("{js} threw: {}", details.text);
    }
    result.result.value.unwrap_or(serde_json::Value::Null)
}

/// Waits until the page's hooks exist and a frame has settled; the page's message instead where
/// it failed. Returns the milliseconds from the navigation's start to the settled frame.
fn settled(tab: &Tab) -> f64 {
    let out = eval(
        tab,
        r#"new Promise((resolve) => {
            const poll = () => {
              const m = document.getElementById('message');
              if (window.terrain && window.terrain.settled) {
                window.terrain.settled().then(() => resolve({ ms: performance.now() }));
              } else if (m && !m.hidden && /:/.test(m.textContent)) {
                resolve({ failed: m.textContent });
              } else {
                setTimeout(poll, 20);
              }
            };
            poll();
          })"#,
    );
    if let Some(why) = out.get("failed") {
        panic!("the page failed: {why}");
    }
    out["ms"].as_f64().expect("a time")
}

/// The canvas's pixels (RGBA) as the next frame leaves its texture (`window.terrain.capture()`),
/// the canvas `side` pixels square.
fn canvas_rgba(tab: &Tab, side: u32) -> Vec<u8> {
    use base64::Engine;
    let text = eval(
        tab,
        r#"window.terrain.capture().then((px) => {
             let s = '';
             for (let i = 0; i < px.length; i += 0x8000) {
               s += String.fromCharCode.apply(null, px.subarray(i, i + 0x8000));
             }
             return btoa(s);
           })"#,
    );
    let rgba = base64::engine::general_purpose::STANDARD
        .decode(text.as_str().expect("base64 text"))
        .unwrap();
    assert_eq!(rgba.len(), (side * side * 4) as usize, "the canvas's size");
    rgba
}

fn write_png(path: &Path, rgba: &[u8]) {
    terrain_cli::output::write_image(path, SIZE, SIZE, rgba).unwrap();
}

/// The bundled scene (warped) and a user's GeoTIFF (written by GDAL; GeoMipMap, whose bake the
/// page reads back without waiting), each exported, served and opened with `?still=1`: the
/// canvas against `terrain render` of the same scene, mode and size.
fn the_page_draws_what_render_draws_for_the_bundled_scene_and_a_users_geotiff() {
    let root = manifest_dir();
    let sources = [
        ("jacksboro", root.join("sketches/jacksboro.toml"), "warped"),
        (
            "geotiff",
            root.join("tests/data/formats/utm-metres-Float32.tif"),
            "geomipmap",
        ),
    ];
    for (name, source, mode) in sources {
        let dir = scratch(&format!("web-{name}"));
        let site = serve(&source, &dir.join("site"), &["--mode", mode]);
        // A browser each: SwiftShader, still busy with one page's frames, keeps a second tab
        // from opening within the protocol's timeout.
        let browser = browser();
        let tab = browser.new_tab().unwrap();
        tab.set_default_timeout(Duration::from_secs(300));
        let errors = console_errors(&tab);
        tab.navigate_to(&format!("{}?still=1", site.url)).unwrap();
        let first_frame_ms = settled(&tab);
        let page = canvas_rgba(&tab, SIZE);
        let stats = eval(&tab, "window.terrain.stats()");
        let reference = rendered_rgba_with(&source, &dir, SIZE, &["--mode", mode]);
        let db = psnr(&page, &reference);
        write_png(&dir.join("page.png"), &page);
        eprintln!(
            "web {name}: PSNR {db:.2} dB against render; first frame {first_frame_ms:.0} ms \
             after navigation; stats {stats}"
        );
        assert!(
            db >= 30.0,
            "{name}: the page's still is {db:.2} dB from render's (page.png and render.png in {})",
            dir.display()
        );
        assert_eq!(stats["mode"], mode);
        assert!(stats["triangles"].as_f64().unwrap() > 1000.0, "{stats}");
        assert!(
            stats["adapter"]
                .as_str()
                .unwrap()
                .to_lowercase()
                .contains("swiftshader"),
            "{stats}"
        );
        let errors = errors.lock().unwrap();
        assert!(errors.is_empty(), "{name}: {errors:?}");
        // The README's picture of the page.
        if name == "jacksboro" {
            std::fs::copy(dir.join("page.png"), root.join("target/web-page.png")).ok();
        }
    }
}

/// The bundled scene flown along its path for sixty frames (the picture moves), then switched to
/// GeoMipMap (its bake read back while the warped mode goes on drawing) and to the wireframe
/// view, drawing frames: no console error.
fn the_page_flies_its_path_and_switches_mode_and_view_without_a_console_error() {
    let dir = scratch("web-fly");
    let site = serve(
        &manifest_dir().join("sketches/jacksboro.toml"),
        &dir.join("site"),
        &[],
    );
    let browser = browser();
    let tab = browser.new_tab().unwrap();
    tab.set_default_timeout(Duration::from_secs(300));
    let errors = console_errors(&tab);
    tab.call_method(Emulation::SetDeviceMetricsOverride {
        width: FLIGHT_VIEWPORT,
        height: FLIGHT_VIEWPORT,
        device_scale_factor: 1.0,
        mobile: false,
        scale: None,
        screen_width: None,
        screen_height: None,
        position_x: None,
        position_y: None,
        dont_set_visible_size: None,
        screen_orientation: None,
        viewport: None,
        display_feature: None,
        device_posture: None,
    })
    .unwrap();
    // Headless Chromium cannot show a WebGPU canvas here (its GPU process cannot make the swap
    // chain's image on SwiftShader, and drops the page's WebGPU): the frames are copied.
    tab.navigate_to(&format!("{}?present=copy", site.url))
        .unwrap();
    settled(&tab);
    let frames = |n: u32| {
        eval(
            &tab,
            &format!(
                "new Promise((resolve) => {{
                   const poll = () => window.terrain.stats().frames >= {n}
                     ? resolve(window.terrain.stats()) : requestAnimationFrame(poll);
                   poll();
                 }})"
            ),
        )
    };
    frames(2);
    let early = canvas_rgba(&tab, FLIGHT_VIEWPORT);
    let flown = frames(60);
    let late = canvas_rgba(&tab, FLIGHT_VIEWPORT);
    let moved = psnr(&early, &late);
    eprintln!(
        "web flight: 60 frames, stats {flown}; first and sixtieth frames {moved:.1} dB apart"
    );
    assert!(
        moved < 40.0,
        "the path did not move the camera ({moved:.1} dB)"
    );
    assert_eq!(flown["mode"], "warped");
    let fps = 1000.0 / flown["frame_ms"].as_f64().unwrap();
    assert!(fps.is_finite() && fps > 0.0, "{flown}");

    // The comparison users come for: GeoMipMap's button. Until its bake is back the warped
    // mode draws on and `coming` names it; then its frames count from 0.
    let modes = eval(
        &tab,
        "[...document.querySelectorAll('#controls button')].map((b) => b.textContent)",
    );
    eprintln!("web flight: the page's buttons {modes}");
    let clicked = eval(
        &tab,
        "(() => { const b = [...document.querySelectorAll('#controls button')]
             .find((b) => b.textContent === 'GeoMipMap');
           if (!b) return false; window.clicked = performance.now(); b.click(); return true; })()",
    );
    assert_eq!(clicked, true, "no GeoMipMap button among {modes}");
    let switched = eval(
        &tab,
        "new Promise((resolve) => {
           const poll = () => {
             const s = window.terrain.stats();
             s.mode === 'geomipmap' && s.frames >= 10
               ? resolve({ ...s, since_click_ms: performance.now() - window.clicked })
               : requestAnimationFrame(poll);
           };
           poll();
         })",
    );
    eprintln!("web flight: GeoMipMap, stats {switched}");
    assert_eq!(switched["coming"], "", "{switched}");
    assert!(
        switched["triangles"].as_f64().unwrap() > 1000.0,
        "{switched}"
    );
    eval(&tab, "window.terrain.setView('wireframe')");
    let wire = frames(10);
    assert_eq!(wire["view"], "wireframe", "{wire}");
    assert_eq!(wire["mode"], "geomipmap", "{wire}");
    let errors = errors.lock().unwrap();
    assert!(errors.is_empty(), "{errors:?}");
}

/// A browser without WebGPU (here `navigator.gpu` taken away before the page runs) shows the
/// page's message, naming WebGPU.
fn a_browser_without_webgpu_gets_a_message_not_a_blank_page() {
    let dir = scratch("web-nogpu");
    // The page says so before it loads the module: a stand-in module serves.
    let pkg = dir.join("pkg");
    std::fs::create_dir_all(&pkg).unwrap();
    std::fs::write(
        pkg.join("terrain_web.js"),
        "export default function init() {}",
    )
    .unwrap();
    std::fs::write(pkg.join("terrain_web_bg.wasm"), b"\0asm\x01\0\0\0").unwrap();
    let jacksboro = manifest_dir().join("sketches/jacksboro.toml");
    let site = serve(
        &jacksboro,
        &dir.join("site"),
        &["--pkg", pkg.to_str().unwrap()],
    );
    let browser = browser();
    let tab = browser.new_tab().unwrap();
    tab.set_default_timeout(Duration::from_secs(60));
    tab.call_method(Page::AddScriptToEvaluateOnNewDocument {
        source: "Object.defineProperty(navigator, 'gpu', { value: undefined });".into(),
        world_name: None,
        include_command_line_api: None,
        run_immediately: None,
    })
    .unwrap();
    tab.navigate_to(&site.url).unwrap();
    let text = eval(
        &tab,
        r#"new Promise((resolve) => {
            const poll = () => {
              const m = document.getElementById('message').textContent;
              /WebGPU/.test(m) ? resolve(m) : setTimeout(poll, 20);
            };
            poll();
          })"#,
    );
    assert!(text.as_str().unwrap().contains("has no WebGPU"), "{text}");
}
