//! `compare.html` in a real browser: the page is rendered by headless
//! Chromium (Debian's `chromium`, which `.ci/run` installs) and the
//! screenshot must show the page's pictures and plots, not a blank or an
//! error page. Without Chromium on the PATH the test says so and checks the
//! page text only.

use isomorph_cli::methods::{Method, Settings, build, load_input};
use isomorph_common::Control;
use isomorph_io::compare::{Candidate, compare};
use isomorph_io::export::ExportSettings;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Chromium's executable, when installed.
fn chromium() -> Option<PathBuf> {
    ["chromium", "chromium-browser", "google-chrome"].iter().find_map(|name| {
        let out = Command::new("sh").arg("-c").arg(format!("command -v {name}")).output().ok()?;
        out.status.success().then(|| PathBuf::from(String::from_utf8_lossy(&out.stdout).trim()))
    })
}

/// Renders `page` to `png` with headless Chromium.
fn screenshot(browser: &Path, page: &Path, png: &Path) {
    let status = Command::new(browser)
        .args(["--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars", "--window-size=1280,1600"])
        .arg(format!("--screenshot={}", png.display()))
        .arg(format!("file://{}", page.display()))
        .status()
        .expect("chromium starts");
    assert!(status.success(), "chromium failed: {status}");
}

/// The distinct gray levels among the image's pixels (a blank page has one
/// or two).
fn distinct_colours(png: &Path) -> usize {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(png).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0u8; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = info.color_type.samples();
    let mut seen = std::collections::HashSet::new();
    for px in buf[..info.buffer_size()].chunks(channels) {
        seen.insert(px[..3.min(channels)].to_vec());
    }
    seen.len()
}

#[test]
fn compare_page_renders_in_a_browser() {
    let dir = std::env::temp_dir().join(format!("isomorph-compare-page-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let candidates = [Method::Baseline, Method::Rbf]
        .into_iter()
        .map(|method| {
            let source = load_input(method, "sphere", &Default::default()).unwrap();
            let target = load_input(method, "torus", &Default::default()).unwrap();
            let settings = Settings::default().with_resolution(32);
            Candidate {
                name: method.name().to_string(),
                build: Ok(Box::new(move |c: &Control| build(method, &source, &target, &settings, c))),
                references: None,
            }
        })
        .collect();
    let settings =
        ExportSettings { frames: 3, resolution: 32, out_dir: dir.clone(), ..ExportSettings::default() };
    compare("sphere", "torus", candidates, &settings, &Control::new()).unwrap();
    let page = dir.join("compare.html");
    let text = std::fs::read_to_string(&page).unwrap();
    // Self-contained: no external pictures, scripts or styles.
    assert!(!text.contains("src=\"http") && !text.contains("href=\"http"), "the page loads from the network");
    assert!(text.contains("data:image/png;base64,") && text.contains("<svg"), "no sheet or plots");
    let Some(browser) = chromium() else {
        eprintln!("chromium is not installed: the page was checked as text only");
        return;
    };
    let shot = dir.join("screenshot.png");
    screenshot(&browser, &page, &shot);
    let colours = distinct_colours(&shot);
    // The sheet's shaded meshes and the coloured plot lines give thousands.
    assert!(colours > 200, "the screenshot looks blank: {colours} colours");
    let _ = std::fs::remove_dir_all(&dir);
}
