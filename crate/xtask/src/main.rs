//! Odori's build tool.
//!
//! - `build-web [--dev] [--only full|player]`: cargo (wasm32) → wasm-bindgen → wasm-opt →
//!   `pkg/` with its `package.json`, driven by `wasm-pack.toml`; then the player build (the
//!   same crate without authoring) → `pkg/player/` with the `<odori-player>` element. Uses the active rustc's wasm32 std when it has
//!   one; otherwise builds std from source with Debian's `rustc-web`/`cargo-web` (see
//!   ../shared guides and the README).
//! - `serve [--port N]`: a static server for the app (`/` → `www/`, `/pkg/` → `pkg/`,
//!   `/examples/` → `examples/`), on
//!   127.0.0.1, printing the URL.
//! - `check-core-deps`: fails when the core's dependency tree contains a web crate.
//! - `test-native [cargo test args]`: the native tests, one test binary per core, longest first
//!   (`native_tests.rs`).

mod native_tests;

use std::io::{BufRead, BufReader, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{exit, Command};

use serde::Deserialize;

#[derive(Deserialize)]
struct Settings {
    package: PackageSettings,
    toolchain: ToolchainSettings,
    player: PlayerSettings,
    profile: std::collections::BTreeMap<String, ProfileSettings>,
}

#[derive(Deserialize)]
#[serde(rename_all = "kebab-case")]
struct PackageSettings {
    #[serde(rename = "crate")]
    krate: String,
    out_dir: String,
    out_name: String,
    target: String,
    npm_name: String,
    description: String,
}

/// The second build: the bindings crate with other cargo features, plus the element's files.
#[derive(Deserialize)]
#[serde(rename_all = "kebab-case")]
struct PlayerSettings {
    out_dir: String,
    out_name: String,
    no_default_features: bool,
    features: Vec<String>,
    /// A folder whose files are copied into `out_dir` (the custom element).
    element: String,
    /// Overrides of the release profile for this build (size over speed), if any.
    #[serde(default)]
    release: Option<PlayerRelease>,
}

#[derive(Deserialize)]
#[serde(rename_all = "kebab-case")]
struct PlayerRelease {
    cargo_profile: String,
    wasm_opt: Vec<String>,
    /// Minify the player's JavaScript (the bindings and the element) with esbuild from
    /// node_modules: the download is the point of the player build.
    #[serde(default)]
    minify_js: bool,
    /// rustc flags for this build only, after `[toolchain] rustflags` (e.g. `-Z` size flags).
    #[serde(default)]
    rustflags: Vec<String>,
}

#[derive(Deserialize)]
#[serde(rename_all = "kebab-case")]
struct ToolchainSettings {
    wasm_bindgen: String,
    target: String,
    /// Extra rustc flags for the wasm target only (not for build scripts on the host).
    #[serde(default)]
    rustflags: Vec<String>,
}

#[derive(Deserialize)]
#[serde(rename_all = "kebab-case")]
struct ProfileSettings {
    cargo_profile: String,
    wasm_opt: Vec<String>,
    keep_debug_names: bool,
    /// rustc flags of this build added to `[toolchain] rustflags`.
    #[serde(default)]
    rustflags: Vec<String>,
}

/// The checkout to work on: the current directory when it is one (so a `target/` copied from
/// another checkout, with that checkout's path compiled in, still serves and builds this one),
/// else the checkout this binary was built from.
fn root() -> PathBuf {
    let is_checkout = |d: &std::path::Path| d.join("crate/xtask/Cargo.toml").is_file() && d.join("www").is_dir();
    if let Ok(cwd) = std::env::current_dir() {
        if is_checkout(&cwd) {
            return cwd;
        }
    }
    match PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize() {
        Ok(p) => p,
        Err(e) => fail(format!("the repository root ({}/../..) is gone ({e}); run from the checkout", env!("CARGO_MANIFEST_DIR"))),
    }
}

fn fail(msg: impl AsRef<str>) -> ! {
    eprintln!("xtask: {}", msg.as_ref());
    exit(1)
}

fn run(cmd: &mut Command) {
    eprintln!("+ {:?}", cmd);
    match cmd.status() {
        Ok(s) if s.success() => {}
        Ok(s) => fail(format!("command failed ({s}): {cmd:?}")),
        Err(e) => fail(format!("cannot run {cmd:?}: {e}")),
    }
}

fn output(cmd: &mut Command) -> Option<String> {
    cmd.output().ok().filter(|o| o.status.success()).map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
}

/// Does this rustc have a prebuilt std for the target?
fn has_target_std(rustc: &str, target: &str) -> bool {
    let Some(dir) = output(Command::new(rustc).args(["--print", "target-libdir", "--target", target])) else { return false };
    std::fs::read_dir(&dir).map(|d| d.flatten().any(|e| e.file_name().to_string_lossy().starts_with("libstd-"))).unwrap_or(false)
}

/// The file name cargo gives the crate's cdylib: its `[lib] name`, read from `cargo metadata`.
fn cdylib_name(root: &Path, krate: &str) -> String {
    let meta = output(Command::new("cargo").current_dir(root).args(["metadata", "--no-deps", "--format-version", "1"]))
        .unwrap_or_else(|| fail("cargo metadata failed"));
    let meta: serde_json::Value = serde_json::from_str(&meta).unwrap_or_else(|e| fail(format!("cargo metadata: {e}")));
    meta["packages"]
        .as_array()
        .into_iter()
        .flatten()
        .filter(|p| p["name"] == krate)
        .flat_map(|p| p["targets"].as_array().into_iter().flatten())
        .find(|t| t["kind"].as_array().is_some_and(|k| k.iter().any(|k| k == "cdylib")))
        .and_then(|t| t["name"].as_str())
        .map(|n| n.replace('-', "_"))
        .unwrap_or_else(|| fail(format!("package {krate} has no cdylib target")))
}

/// One wasm build: cargo with these feature flags → wasm-bindgen → wasm-opt into `out_dir`.
/// Returns (bytes after wasm-bindgen, bytes after wasm-opt).
fn build_wasm(root: &Path, settings: &Settings, profile: &ProfileSettings, feature_args: &[String], out_dir: &Path, out_name: &str) -> (u64, u64) {
    let target = &settings.toolchain.target;
    let started = std::time::Instant::now();

    // 1. cargo build for wasm32.
    let mut cargo;
    if has_target_std("rustc", target) {
        cargo = Command::new("cargo");
    } else if Path::new("/usr/bin/cargo").exists() && Path::new("/usr/bin/rustc").exists() {
        // Debian's rustc-web: build std from its sources (rust-web-src), link with lld-19.
        cargo = Command::new("/usr/bin/cargo");
        cargo
            .env("RUSTC", "/usr/bin/rustc")
            .env("RUSTDOC", "/usr/bin/rustdoc")
            .env("RUSTC_BOOTSTRAP", "1")
            .env("CARGO_UNSTABLE_BUILD_STD", "std,panic_abort")
            .env("CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_LINKER", "wasm-ld-19");
    } else {
        fail("no Rust toolchain with a wasm32 std: run ./dev setup (installs rustc-web, cargo-web, rust-web-src, lld-19)");
    }
    cargo.current_dir(root).args(["build", "--target", target, "-p", &settings.package.krate, "--profile", &profile.cargo_profile]).args(feature_args);
    let rustflags: Vec<&str> = settings.toolchain.rustflags.iter().chain(&profile.rustflags).map(String::as_str).collect();
    if !rustflags.is_empty() {
        let var = format!("CARGO_TARGET_{}_RUSTFLAGS", target.to_uppercase().replace(['-', '.'], "_"));
        cargo.env(var, rustflags.join(" "));
    }
    // `-Z` flags (the player's size flags) need a nightly rustc; the build-std path above runs
    // with RUSTC_BOOTSTRAP already, a plain toolchain is given it for these builds only.
    if rustflags.iter().any(|f| f.starts_with("-Z")) {
        cargo.env("RUSTC_BOOTSTRAP", "1");
    }
    run(&mut cargo);
    let dir_name = if profile.cargo_profile == "dev" { "debug" } else { &profile.cargo_profile };
    let wasm_in = root.join("target").join(target).join(dir_name).join(format!("{}.wasm", cdylib_name(root, &settings.package.krate)));
    if !wasm_in.exists() {
        fail(format!("expected {} after the cargo build", wasm_in.display()));
    }

    // 2. wasm-bindgen, the pinned version.
    let version = output(Command::new("wasm-bindgen").arg("--version")).unwrap_or_default();
    if !version.ends_with(&settings.toolchain.wasm_bindgen) {
        fail(format!(
            "wasm-bindgen {} is needed (found '{version}'): cargo install wasm-bindgen-cli --version {}",
            settings.toolchain.wasm_bindgen, settings.toolchain.wasm_bindgen
        ));
    }
    std::fs::create_dir_all(out_dir).unwrap_or_else(|e| fail(format!("create {}: {e}", out_dir.display())));
    let mut wb = Command::new("wasm-bindgen");
    wb.arg(&wasm_in).arg("--out-dir").arg(out_dir).args(["--out-name", out_name, "--target", &settings.package.target]);
    if profile.keep_debug_names {
        wb.arg("--keep-debug");
    }
    run(&mut wb);

    // 3. wasm-opt from node_modules (npm's binaryen).
    let wasm_out = out_dir.join(format!("{out_name}_bg.wasm"));
    let raw = std::fs::metadata(&wasm_out).map(|m| m.len()).unwrap_or(0);
    if !profile.wasm_opt.is_empty() {
        let wasm_opt = root.join("node_modules/.bin/wasm-opt");
        if !wasm_opt.exists() {
            fail("node_modules/.bin/wasm-opt is missing: run npm install (./dev setup does)");
        }
        let tmp = out_dir.join("opt.wasm");
        run(Command::new(&wasm_opt).args(&profile.wasm_opt).arg(&wasm_out).arg("-o").arg(&tmp));
        std::fs::rename(&tmp, &wasm_out).expect("replace wasm");
    }
    let opt = std::fs::metadata(&wasm_out).map(|m| m.len()).unwrap_or(0);
    eprintln!("xtask: {} ready in {:.0} s: raw {raw} bytes, after wasm-opt {opt} bytes", wasm_out.display(), started.elapsed().as_secs_f64());
    (raw, opt)
}

/// The player build: the same crate with the player's features, its own folder, the element's
/// files beside it, and in release its own cargo profile, wasm-opt flags and minified JS.
fn build_player_package(root: &Path, settings: &Settings, profile: &ProfileSettings, dev: bool) {
    let player = &settings.player;
    let player_dir = root.join(&player.out_dir);
    let mut args = Vec::new();
    if player.no_default_features {
        args.push("--no-default-features".to_string());
    }
    if !player.features.is_empty() {
        args.push("--features".into());
        args.push(player.features.join(","));
    }
    // In release, the player may use its own cargo profile and wasm-opt flags.
    let own = match (&player.release, dev) {
        (Some(r), false) => Some(ProfileSettings {
            cargo_profile: r.cargo_profile.clone(),
            wasm_opt: r.wasm_opt.clone(),
            keep_debug_names: profile.keep_debug_names,
            rustflags: r.rustflags.clone(),
        }),
        _ => None,
    };
    build_wasm(root, settings, own.as_ref().unwrap_or(profile), &args, &player_dir, &player.out_name);
    let element = root.join(&player.element);
    let files = std::fs::read_dir(&element).unwrap_or_else(|e| fail(format!("{}: {e}", element.display())));
    for f in files.flatten().filter(|f| f.path().is_file()) {
        std::fs::copy(f.path(), player_dir.join(f.file_name())).unwrap_or_else(|e| fail(format!("copy {}: {e}", f.path().display())));
    }
    if !dev && player.release.as_ref().is_some_and(|r| r.minify_js) {
        let esbuild = root.join("node_modules/.bin/esbuild");
        if !esbuild.exists() {
            fail("node_modules/.bin/esbuild is missing: run npm install (./dev setup does)");
        }
        let js = std::fs::read_dir(&player_dir).unwrap_or_else(|e| fail(format!("{}: {e}", player_dir.display())));
        for f in js.flatten().map(|f| f.path()).filter(|p| p.extension().is_some_and(|e| e == "js")) {
            let before = std::fs::metadata(&f).map(|m| m.len()).unwrap_or(0);
            run(Command::new(&esbuild).arg(&f).args(["--minify", "--format=esm", "--target=es2022", "--log-level=warning", "--allow-overwrite"]).arg(format!("--outfile={}", f.display())));
            let after = std::fs::metadata(&f).map(|m| m.len()).unwrap_or(0);
            eprintln!("xtask: {} minified: {before} -> {after} bytes", f.display());
        }
    }
}

fn build_web(dev: bool, only: Option<&str>) {
    let root = root();
    let settings: Settings = toml::from_str(&std::fs::read_to_string(root.join("wasm-pack.toml")).expect("wasm-pack.toml"))
        .unwrap_or_else(|e| fail(format!("wasm-pack.toml: {e}")));
    let profile_name = if dev { "dev" } else { "release" };
    let profile = settings.profile.get(profile_name).unwrap_or_else(|| fail(format!("wasm-pack.toml has no [profile.{profile_name}]")));
    let (build_full, build_player) = match only {
        None => (true, true),
        Some("full") => (true, false),
        Some("player") => (false, true),
        Some(other) => fail(format!("--only takes full or player, not '{other}'")),
    };
    let out_dir = root.join(&settings.package.out_dir);
    let name = &settings.package.out_name;

    // The two builds run side by side: they use different cargo profiles (release and
    // release-player), so different folders and locks under target/, and each spends long
    // stretches on one core (the fat-LTO link, wasm-bindgen, much of wasm-opt) that the other
    // fills (this machine kind has 2 cores).
    // A dev build uses one profile for both (one output file), so there they run one after the other.
    let side_by_side = settings.player.release.as_ref().is_some_and(|r| !dev && r.cargo_profile != profile.cargo_profile);
    std::thread::scope(|scope| {
        // The full engine: the crate's default features.
        let full = (build_full && side_by_side).then(|| scope.spawn(|| build_wasm(&root, &settings, profile, &[], &out_dir, name)));
        if build_full && !side_by_side {
            build_wasm(&root, &settings, profile, &[], &out_dir, name);
        }
        if build_player {
            build_player_package(&root, &settings, profile, dev);
        }
        if let Some(full) = full {
            full.join().unwrap_or_else(|_| fail("the full engine's build panicked"));
        }
    });
    let player = &settings.player;
    let player_dir = root.join(&player.out_dir);

    // 4. package.json for npm consumers: `odori` is the full engine, `odori/player` the element
    //    with the player build (the path of the player folder inside the package).
    let player_rel = player_dir.strip_prefix(&out_dir).unwrap_or_else(|_| fail("[player] out-dir must be inside [package] out-dir")).to_string_lossy().replace('\\', "/");
    let version = output(Command::new("cargo").current_dir(&root).args(["pkgid", "-p", &settings.package.krate]))
        .and_then(|s| s.rsplit(['@', '#']).next().map(str::to_string))
        .unwrap_or_else(|| "0.0.0".into());
    let pname = &player.out_name;
    // A struct, not `json!`: serde_json's map sorts keys, and in an `exports` condition object
    // "types" must come before "default" (the first matching condition wins).
    #[derive(serde::Serialize)]
    struct Cond {
        types: String,
        default: String,
    }
    #[derive(serde::Serialize)]
    #[serde(untagged)]
    enum Entry {
        Cond(Cond),
        Path(String),
    }
    /// A map written in the order given.
    struct Ordered(Vec<(String, Entry)>);
    impl serde::Serialize for Ordered {
        fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
            use serde::ser::SerializeMap;
            let mut m = s.serialize_map(Some(self.0.len()))?;
            for (k, v) in &self.0 {
                m.serialize_entry(k, v)?;
            }
            m.end()
        }
    }
    let cond = |types: String, default: String| Entry::Cond(Cond { types, default });
    let exports = Ordered(vec![
        (".".into(), cond(format!("./{name}.d.ts"), format!("./{name}.js"))),
        ("./player".into(), cond(format!("./{player_rel}/odori-player.d.ts"), format!("./{player_rel}/odori-player.js"))),
        ("./player/engine".into(), cond(format!("./{player_rel}/{pname}.d.ts"), format!("./{player_rel}/{pname}.js"))),
        ("./video".into(), Entry::Path("./video/export-video.js".into())),
        (format!("./{name}_bg.wasm"), Entry::Path(format!("./{name}_bg.wasm"))),
        (format!("./player/{pname}_bg.wasm"), Entry::Path(format!("./{player_rel}/{pname}_bg.wasm"))),
        ("./package.json".into(), Entry::Path("./package.json".into())),
    ]);
    #[derive(serde::Serialize)]
    #[serde(rename_all = "camelCase")]
    struct Package<'a> {
        name: &'a str,
        version: String,
        description: &'a str,
        license: &'a str,
        #[serde(rename = "type")]
        kind: &'a str,
        main: String,
        module: String,
        types: String,
        exports: Ordered,
        files: Vec<String>,
        side_effects: Vec<String>,
        keywords: Vec<&'a str>,
    }
    let pkg = Package {
        name: &settings.package.npm_name,
        version,
        description: &settings.package.description,
        license: "MIT OR Apache-2.0",
        kind: "module",
        main: format!("{name}.js"),
        module: format!("{name}.js"),
        types: format!("{name}.d.ts"),
        exports,
        files: vec![format!("{name}_bg.wasm"), format!("{name}.js"), format!("{name}.d.ts"), format!("{name}_bg.wasm.d.ts"), format!("{player_rel}/"), "video/".into(), "README.md".into()],
        side_effects: vec!["./snippets/*".into(), format!("./{player_rel}/odori-player.js")],
        keywords: vec!["dance", "motion", "animation", "bvh", "gltf", "wasm", "webgpu", "web-component"],
    };
    std::fs::write(out_dir.join("package.json"), serde_json::to_string_pretty(&pkg).unwrap() + "\n").expect("write package.json");
    eprintln!("xtask: pkg/ ready (full engine in {}, player in {})", out_dir.display(), player_dir.display());

    // 5. The app's one npm runtime module, vendored so the page (static files, no bundler)
    //    loads it offline: idb, the IndexedDB wrapper autosave uses (www/project/store.js).
    let idb = root.join("node_modules/idb/build/index.js");
    if !idb.exists() {
        fail("node_modules/idb is missing: run npm install (./dev setup does)");
    }
    std::fs::create_dir_all(root.join("www/vendor")).expect("create www/vendor/");
    std::fs::copy(&idb, root.join("www/vendor/idb.js")).expect("copy idb into www/vendor/");

    // 6. The video export (issue 29): www/video/export-video.js imports Mediabunny (the MP4 /
    //    WebM muxer) from beside itself. esbuild bundles only what it uses
    //    (www/video/mediabunny-entry.js, tree-shaken: about 255 kB against the 689 kB of
    //    Mediabunny's whole minified build) into www/video/mediabunny.js (not committed) and,
    //    with the module, into the package's full engine (pkg/video/: `import { exportVideo }
    //    from "odori/video"`).
    if !root.join("node_modules/mediabunny/package.json").exists() {
        fail("node_modules/mediabunny is missing: run npm install (./dev setup does)");
    }
    let bundled = root.join("www/video/mediabunny.js");
    run(Command::new(root.join("node_modules/.bin/esbuild"))
        .arg(root.join("www/video/mediabunny-entry.js"))
        .args(["--bundle", "--minify", "--format=esm", "--target=es2022", "--log-level=warning"])
        .arg(format!("--outfile={}", bundled.display())));
    let video_dir = out_dir.join("video");
    std::fs::create_dir_all(&video_dir).expect("create pkg/video/");
    std::fs::copy(&bundled, video_dir.join("mediabunny.js")).expect("copy mediabunny into pkg/video/");
    std::fs::copy(root.join("www/video/export-video.js"), video_dir.join("export-video.js")).expect("copy export-video.js into pkg/video/");
}

fn content_type(path: &Path) -> &'static str {
    match path.extension().and_then(|e| e.to_str()).unwrap_or("") {
        "html" => "text/html; charset=utf-8",
        "js" | "mjs" => "text/javascript; charset=utf-8",
        "css" => "text/css; charset=utf-8",
        "wasm" => "application/wasm",
        "json" | "webmanifest" => "application/json",
        "svg" => "image/svg+xml",
        "png" => "image/png",
        "ts" => "text/plain; charset=utf-8",
        "glb" => "model/gltf-binary",
        "ogg" => "audio/ogg",
        "wav" => "audio/wav",
        _ => "application/octet-stream",
    }
}

fn respond(mut stream: TcpStream, www: &Path, pkg: &Path, examples: &Path) {
    let mut reader = BufReader::new(stream.try_clone().expect("clone stream"));
    let mut request_line = String::new();
    if reader.read_line(&mut request_line).is_err() {
        return;
    }
    // Drain headers.
    let mut line = String::new();
    while reader.read_line(&mut line).map(|n| n > 2).unwrap_or(false) {
        line.clear();
    }
    let mut parts = request_line.split_whitespace();
    let (method, target) = (parts.next().unwrap_or(""), parts.next().unwrap_or("/"));
    let path = target.split(['?', '#']).next().unwrap_or("/");
    let path = percent_decode(path);
    let (base, rel) = if let Some(rest) = path.strip_prefix("/pkg/") {
        (pkg, rest.to_string())
    } else if let Some(rest) = path.strip_prefix("/examples/") {
        (examples, rest.to_string())
    } else {
        (www, path.trim_start_matches('/').to_string())
    };
    let rel = if rel.is_empty() || rel.ends_with('/') { format!("{rel}index.html") } else { rel };
    let file = base.join(&rel);
    let safe = !rel.split('/').any(|c| c == "..") && file.starts_with(base);
    let (status, body, ctype) = match (safe, std::fs::read(&file)) {
        (true, Ok(b)) => ("200 OK", b, content_type(&file)),
        _ => ("404 Not Found", format!("not found: {path}\n").into_bytes(), "text/plain; charset=utf-8"),
    };
    let head = format!(
        "HTTP/1.1 {status}\r\nContent-Type: {ctype}\r\nContent-Length: {}\r\nCache-Control: no-cache\r\nCross-Origin-Opener-Policy: same-origin\r\nConnection: close\r\n\r\n",
        body.len()
    );
    let _ = stream.write_all(head.as_bytes());
    if method != "HEAD" {
        let _ = stream.write_all(&body);
    }
    let _ = stream.flush();
}

fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            if let Ok(v) = u8::from_str_radix(&s[i + 1..i + 3], 16) {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn serve(port: u16) {
    let root = root();
    let (www, pkg, examples) = (root.join("www"), root.join("pkg"), root.join("examples"));
    if !pkg.join("odori_bg.wasm").exists() {
        fail("pkg/odori_bg.wasm is missing: build first (./dev serve does)");
    }
    let listener = TcpListener::bind(("127.0.0.1", port)).unwrap_or_else(|e| fail(format!("cannot listen on 127.0.0.1:{port}: {e}")));
    let port = listener.local_addr().map(|a| a.port()).unwrap_or(port);
    println!("Odori is served at http://localhost:{port}/  (Ctrl-C stops)");
    let _ = std::io::stdout().flush();
    for stream in listener.incoming().flatten() {
        let (www, pkg, examples) = (www.clone(), pkg.clone(), examples.clone());
        std::thread::spawn(move || respond(stream, &www, &pkg, &examples));
    }
}

fn check_core_deps() {
    let root = root();
    let tree = output(Command::new("cargo").current_dir(&root).args(["tree", "-p", "odori-core", "-e", "normal,build", "--prefix", "none", "--target", "all"]))
        .unwrap_or_else(|| fail("cargo tree failed"));
    let banned = ["wasm-bindgen", "web-sys", "js-sys", "wgpu", "serde-wasm-bindgen", "console_error_panic_hook"];
    let found: Vec<&str> = tree.lines().filter(|l| banned.iter().any(|b| l.split_whitespace().next() == Some(b))).collect();
    if !found.is_empty() {
        fail(format!("the core's dependency tree contains web crates: {found:?}"));
    }
    println!("core dependency tree: {} crates, none of {banned:?}", tree.lines().collect::<std::collections::BTreeSet<_>>().len());
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("build-web") => {
            let only = args.iter().position(|a| a == "--only").and_then(|i| args.get(i + 1)).map(String::as_str);
            build_web(args.iter().any(|a| a == "--dev"), only)
        }
        Some("serve") => {
            let port = args.iter().position(|a| a == "--port").and_then(|i| args.get(i + 1)).and_then(|p| p.parse().ok()).unwrap_or(8080);
            serve(port)
        }
        Some("check-core-deps") => check_core_deps(),
        Some("test-native") => native_tests::run(&root(), &args[1..]),
        _ => fail("usage: xtask build-web [--dev] [--only full|player] | serve [--port N] | check-core-deps | test-native [cargo test args]"),
    }
}
