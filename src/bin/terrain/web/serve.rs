//! `terrain web --serve`: the site's files over HTTP on 127.0.0.1, for a quick look and for the
//! browser tests. Rules: loopback only; files under the site's folder only (a path with `..`
//! or a backslash is refused); each response with its content type, `application/wasm` for
//! the module so the browser compiles it while it arrives; nothing cached, so a site written
//! again shows at once. Rejected: asking users for `python -m http.server`, which serves
//! `.wasm` with a type that some versions get wrong.

use anyhow::{Context, Result};
use std::path::{Component, Path, PathBuf};
use tiny_http::{Header, Response, Server};

/// Serves `root` on 127.0.0.1:`port` until the process ends; prints the address on stdout.
pub fn run(root: &Path, port: u16) -> Result<()> {
    let server = Server::http(("127.0.0.1", port))
        .map_err(|e| anyhow::anyhow!("--serve: cannot listen on 127.0.0.1:{port}: {e}"))?;
    let addr = server
        .server_addr()
        .to_ip()
        .context("--serve: the server has no IP address")?;
    outln!("http://{addr}/");
    eprintln!("serving {} (Ctrl-C stops)", root.display());
    for request in server.incoming_requests() {
        let response = match file_of(root, request.url()) {
            Some(path) => match std::fs::read(&path) {
                Ok(bytes) => Response::from_data(bytes)
                    .with_header(header("Content-Type", content_type(&path)))
                    .with_header(header("Cache-Control", "no-store")),
                Err(_) => not_found(),
            },
            None => not_found(),
        };
        // A browser that went away mid-response is no error of the server's.
        let _ = request.respond(response);
    }
    Ok(())
}

/// The file a request's URL names under `root` (`/` is `index.html`; the query is ignored), or
/// None where it would leave the folder.
fn file_of(root: &Path, url: &str) -> Option<PathBuf> {
    let path = url.split(['?', '#']).next().unwrap_or("");
    let path = percent_decode(path.trim_start_matches('/'))?;
    let rel = match path.as_str() {
        "" => PathBuf::from("index.html"),
        p if p.ends_with('/') => Path::new(p).join("index.html"),
        p => PathBuf::from(p),
    };
    let inside =
        !path.contains('\\') && rel.components().all(|c| matches!(c, Component::Normal(_)));
    inside.then(|| root.join(rel))
}

/// `%20` and the like decoded; None where an escape is cut short or not UTF-8.
fn percent_decode(s: &str) -> Option<String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

fn content_type(path: &Path) -> &'static str {
    match path.extension().and_then(|e| e.to_str()) {
        Some("html") => "text/html; charset=utf-8",
        Some("js") => "text/javascript; charset=utf-8",
        Some("wasm") => "application/wasm",
        Some("json") => "application/json",
        Some("toml") | Some("asc") => "text/plain; charset=utf-8",
        Some("png") => "image/png",
        _ => "application/octet-stream",
    }
}

fn header(name: &str, value: &str) -> Header {
    Header::from_bytes(name, value).expect("ASCII header")
}

fn not_found() -> Response<std::io::Cursor<Vec<u8>>> {
    Response::from_string("not found").with_status_code(404)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn urls_map_to_files_inside_the_site_only() {
        let root = Path::new("/site");
        assert_eq!(file_of(root, "/"), Some(root.join("index.html")));
        assert_eq!(file_of(root, "/?still=1"), Some(root.join("index.html")));
        assert_eq!(file_of(root, "/pkg/a.wasm"), Some(root.join("pkg/a.wasm")));
        assert_eq!(
            file_of(root, "/sketch/my%20dem.tif"),
            Some(root.join("sketch/my dem.tif"))
        );
        assert_eq!(file_of(root, "/../etc/passwd"), None);
        assert_eq!(file_of(root, "/sketch/%2e%2e/%2e%2e/x"), None);
        assert_eq!(file_of(root, "/a\\..\\b"), None);
        assert_eq!(file_of(root, "/%ff"), None);
        assert_eq!(content_type(Path::new("x.wasm")), "application/wasm");
    }
}
