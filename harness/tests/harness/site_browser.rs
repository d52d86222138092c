//! `harness site` in a real headless browser (Debian's `chromium`, driven over the DevTools protocol on its debugging
//! pipe): the site built from the committed results/ loads every page without console errors (each page's load
//! time is printed, not asserted: speed is measured, never gated by a test), the index links every experiment,
//! hovering a known point shows its median from summary.csv, the meshes and peers pages lead with a ratio matrix
//! whose every filled cell is coloured by its verdict (above their figures), every ratio cell on the index and the
//! lead pages is green exactly where its interval lies above 1 (one direction: above 1 = ours faster), each leads
//! with its headline, the index's first screen shows Munich's ambient-occlusion cell, matrix headers stay in view, chart titles and legends stay clear of
//! the plot (and axis titles of tick labels), the series of a chart differ in colour or marker and each keeps its look
//! on every chart of a page, a chart over workloads joins no points, and no page's screenshot is blank. Skipped without chromium, unless
//! `BVHLAB_REQUIRE_BROWSER=1` (CI).

use std::fs::File;
use std::io::{BufRead, BufReader, Write};
use std::os::fd::FromRawFd;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

use serde_json::{Value, json};

/// The chromium binary, if installed; panics when it is not but `BVHLAB_REQUIRE_BROWSER=1` requires it.
fn chromium() -> Option<PathBuf> {
    let found = std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .flat_map(|dir| ["chromium", "chromium-browser"].map(|name| dir.join(name)))
            .find(|path| path.is_file())
    });
    if found.is_none() && std::env::var("BVHLAB_REQUIRE_BROWSER").is_ok_and(|v| v == "1") {
        panic!("BVHLAB_REQUIRE_BROWSER=1 but chromium is not installed (apt-get install chromium)");
    }
    found
}

/// A headless chromium and one attached page session.
struct Browser {
    child: Child,
    commands: File,
    messages: Receiver<Value>,
    next_id: u64,
    session: String,
    /// Events of the page since the last navigation.
    events: Vec<Value>,
    _profile: TempDir,
}

struct TempDir(PathBuf);

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn temp_dir(tag: &str) -> TempDir {
    let dir = std::env::temp_dir().join(format!("bvhlab-site-browser-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    TempDir(dir)
}

/// A pipe whose ends close on exec (the child gets its own copies as fds 3 and 4).
fn pipe() -> (i32, i32) {
    let mut fds = [0; 2];
    assert_eq!(unsafe { libc::pipe2(fds.as_mut_ptr(), libc::O_CLOEXEC) }, 0, "pipe2");
    (fds[0], fds[1])
}

impl Browser {
    /// Starts chromium with a profile of its own (`tag` tells apart browsers of one process).
    fn start(binary: &Path, tag: &str) -> Browser {
        let profile = temp_dir(&format!("profile-{tag}"));
        let (commands_in, commands_out) = pipe(); // the browser reads commands on fd 3
        let (replies_in, replies_out) = pipe(); // and writes replies and events on fd 4
        let mut command = Command::new(binary);
        command
            .args(["--headless=new", "--no-sandbox", "--disable-gpu", "--remote-debugging-pipe", "--no-first-run"])
            .args(["--no-default-browser-check", "--disable-extensions", "--hide-scrollbars", "--window-size=1280,900"])
            .arg(format!("--user-data-dir={}", profile.0.display()))
            .arg("about:blank")
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null());
        unsafe {
            command.pre_exec(move || {
                // Copies above any fd in use first, so that neither target is overwritten before it is read.
                let (read, write) =
                    (libc::fcntl(commands_in, libc::F_DUPFD, 10), libc::fcntl(replies_out, libc::F_DUPFD, 10));
                if read < 0 || write < 0 || libc::dup2(read, 3) < 0 || libc::dup2(write, 4) < 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
        let child = command.spawn().expect("chromium starts");
        unsafe {
            libc::close(commands_in);
            libc::close(replies_out);
        }
        let commands = unsafe { File::from_raw_fd(commands_out) };
        let replies = unsafe { File::from_raw_fd(replies_in) };
        let (send, messages) = channel();
        std::thread::spawn(move || {
            let mut reader = BufReader::new(replies);
            loop {
                let mut message = Vec::new();
                match reader.read_until(0, &mut message) {
                    Ok(0) | Err(_) => break,
                    Ok(_) => {
                        message.pop_if(|b| *b == 0);
                        let Ok(value) = serde_json::from_slice::<Value>(&message) else { continue };
                        if send.send(value).is_err() {
                            break;
                        }
                    }
                }
            }
        });
        let mut browser = Browser {
            child,
            commands,
            messages,
            next_id: 0,
            session: String::new(),
            events: vec![],
            _profile: profile,
        };
        let targets = browser.call("Target.getTargets", json!({}));
        let page = targets["targetInfos"].as_array().unwrap().iter().find(|t| t["type"] == "page").cloned();
        let target = match page {
            Some(page) => page["targetId"].clone(),
            None => browser.call("Target.createTarget", json!({ "url": "about:blank" }))["targetId"].clone(),
        };
        let attached = browser.call("Target.attachToTarget", json!({ "targetId": target, "flatten": true }));
        browser.session = attached["sessionId"].as_str().unwrap().to_string();
        for domain in ["Runtime.enable", "Log.enable", "Page.enable"] {
            browser.call(domain, json!({}));
        }
        let metrics = json!({ "width": 1280, "height": 900, "deviceScaleFactor": 1, "mobile": false });
        browser.call("Emulation.setDeviceMetricsOverride", metrics);
        browser
    }

    /// Sends a command (to the page session once attached) and waits for its reply, keeping the events meanwhile.
    fn call(&mut self, method: &str, params: Value) -> Value {
        self.next_id += 1;
        let id = self.next_id;
        let mut message = json!({ "id": id, "method": method, "params": params });
        if !self.session.is_empty() {
            message["sessionId"] = json!(self.session);
        }
        let mut bytes = message.to_string().into_bytes();
        bytes.push(0);
        self.commands.write_all(&bytes).expect("the browser reads commands");
        loop {
            let reply = self.next_message(method);
            if reply["id"] == id {
                assert!(reply.get("error").is_none(), "{method}: {}", reply["error"]);
                return reply["result"].clone();
            }
            self.events.push(reply);
        }
    }

    fn next_message(&mut self, waiting_for: &str) -> Value {
        self.messages
            .recv_timeout(Duration::from_secs(30))
            .unwrap_or_else(|_| panic!("no answer from chromium within 30 s (waiting for {waiting_for})"))
    }

    /// Opens `url` and waits for its load event.
    fn open(&mut self, url: &str) {
        self.events.clear();
        self.call("Page.navigate", json!({ "url": url }));
        while !self.events.iter().any(|e| e["method"] == "Page.loadEventFired") {
            let event = self.next_message("Page.loadEventFired");
            self.events.push(event);
        }
    }

    /// Exceptions, console errors and logged errors since the last navigation.
    fn errors(&self) -> Vec<String> {
        self.events
            .iter()
            .filter_map(|e| match e["method"].as_str()? {
                "Runtime.exceptionThrown" => Some(e["params"]["exceptionDetails"].to_string()),
                "Runtime.consoleAPICalled" if e["params"]["type"] == "error" => Some(e["params"]["args"].to_string()),
                "Log.entryAdded" if e["params"]["entry"]["level"] == "error" => Some(e["params"]["entry"].to_string()),
                _ => None,
            })
            .collect()
    }

    /// The value of a JavaScript expression.
    fn eval(&mut self, expression: &str) -> Value {
        let result = self.call("Runtime.evaluate", json!({ "expression": expression, "returnByValue": true }));
        assert!(result.get("exceptionDetails").is_none(), "{expression}: {}", result["exceptionDetails"]);
        result["result"]["value"].clone()
    }

    /// How many distinct colours the page's screenshot has.
    fn screenshot_colours(&mut self) -> usize {
        let shot = self.call("Page.captureScreenshot", json!({ "format": "png" }));
        let bytes = base64(shot["data"].as_str().unwrap());
        let mut reader = png::Decoder::new(std::io::Cursor::new(bytes)).read_info().unwrap();
        let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut pixels).unwrap();
        let channels = info.color_type.samples();
        let mut colours: Vec<&[u8]> = pixels[..info.buffer_size()].chunks(channels).collect();
        colours.sort_unstable();
        colours.dedup();
        colours.len()
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn base64(text: &str) -> Vec<u8> {
    let value = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        b'/' => 63,
        _ => panic!("not base64: {c}"),
    };
    let digits: Vec<u8> = text.bytes().filter(|&c| c != b'=').map(value).collect();
    let mut out = Vec::with_capacity(digits.len() * 3 / 4);
    for chunk in digits.chunks(4) {
        let bits = chunk.iter().enumerate().fold(0u32, |acc, (i, &d)| acc | (u32::from(d) << (18 - 6 * i)));
        out.extend(&bits.to_be_bytes()[1..chunk.len()]);
    }
    out
}

/// The experiment folders of results/, as the site should list them (independently of the generator).
fn experiment_folders(results: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(results)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.join("runs.csv").is_file() && p.join("experiment.toml").is_file())
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .filter(|n| n != "baselines" && n != "history" && !n.ends_with("-quick"))
        .collect();
    names.sort();
    names
}

/// The first random-spheres row of results/builds/summary.csv: (series, objects, build_s_median).
fn known_point(results: &Path) -> (String, f64, f64) {
    let mut reader = csv::Reader::from_path(results.join("builds/summary.csv")).unwrap();
    let headers = reader.headers().unwrap().clone();
    let at = |name: &str| headers.iter().position(|h| h == name).unwrap();
    let row = reader.records().map(Result::unwrap).find(|r| &r[at("scene")] == "random-spheres").unwrap();
    (row[at("series")].to_string(), row[at("objects")].parse().unwrap(), row[at("build_s_median")].parse().unwrap())
}

#[test]
fn the_site_of_the_committed_results_works_in_a_browser() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
    let results = root.join("results");
    let out = temp_dir("out");
    let started = Instant::now();
    let status = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args(["site", "--results"])
        .arg(&results)
        .arg("--out")
        .arg(&out.0)
        .status()
        .unwrap();
    assert!(status.success(), "harness site: {status}");
    eprintln!("site built in {:.1} s", started.elapsed().as_secs_f64());
    let Some(binary) = chromium() else {
        eprintln!("skipped: chromium is not installed (set BVHLAB_REQUIRE_BROWSER=1 to require it)");
        return;
    };
    let mut pages: Vec<String> = std::fs::read_dir(&out.0)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".html"))
        .collect();
    pages.sort();
    // The pages are checked by two browsers at once, each taking half.
    let slowest = std::thread::scope(|scope| {
        let (binary, out) = (binary.as_path(), out.0.as_path());
        let halves: Vec<_> = pages
            .chunks(pages.len().div_ceil(2))
            .enumerate()
            .map(|(k, half)| scope.spawn(move || check_pages(binary, out, half, &k.to_string())))
            .collect();
        let slowest = halves.into_iter().map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)));
        slowest.max_by(|a, b| a.0.total_cmp(&b.0)).unwrap_or_default()
    });
    eprintln!("{} pages, slowest load {:.0} ms ({})", pages.len(), slowest.0, slowest.1);

    let mut browser = Browser::start(&binary, "index");
    let url = |page: &str| format!("file://{}", out.0.join(page).display());
    browser.open(&url("index.html"));
    let links = browser.eval("Array.from(document.querySelectorAll('a')).map(a => a.getAttribute('href'))");
    for name in experiment_folders(&results) {
        assert!(links.as_array().unwrap().contains(&json!(format!("{name}.html"))), "index links {name}: {links}");
    }

    let (series, objects, median) = known_point(&results);
    browser.open(&url("builds.html"));
    let selector = format!("figure[data-source=\"chart-0\"] .pt[data-series=\"{series}\"][data-x=\"{objects}\"]");
    let centre = browser.eval(&format!(
        "(() => {{ const p = document.querySelector('{selector}'); p.scrollIntoView({{block: 'center'}});
            const r = p.getBoundingClientRect(); return [r.x + r.width / 2, r.y + r.height / 2]; }})()"
    ));
    let (x, y) = (centre[0].as_f64().unwrap(), centre[1].as_f64().unwrap());
    browser.call("Input.dispatchMouseEvent", json!({ "type": "mouseMoved", "x": x, "y": y }));
    let tip = browser
        .eval("(() => { const t = document.getElementById('tooltip'); return t.hidden ? '' : t.textContent; })()");
    let tip = tip.as_str().unwrap();
    let shown: f64 = tip
        .lines()
        .find_map(|l| l.strip_prefix("median "))
        .unwrap_or_else(|| panic!("no median in the tooltip {tip:?}"))
        .parse()
        .unwrap();
    assert!(tip.starts_with(&series), "{tip}");
    assert!((shown - median).abs() <= 5e-4 * median.abs(), "tooltip median {shown}, summary.csv {median}");
    eprintln!("hover over {series} at {objects} objects: median {shown} (summary.csv {median})");

    // One direction and one colour rule on every page: a cell reads "v [lo, hi]", green (faster) exactly where lo > 1,
    // red (slower) where hi < 1, grey otherwise; the index and each lead page open with a headline.
    let colour_check = "(() => { const bad = []; let n = 0;
        for (const td of document.querySelectorAll('table.matrix tbody td')) {
            const m = td.textContent.match(/^\\s*([0-9.]+)\\s*\\[([0-9.]+),\\s*([0-9.]+)\\]/); if (!m) continue; n++;
            const [v, lo, hi] = [+m[1], +m[2], +m[3]];
            const want = lo > 1 ? 'faster' : hi < 1 ? 'slower' : 'same';
            if (!td.classList.contains(want) || !(lo <= v && v <= hi)) bad.push(td.textContent + ' ' + td.className); }
        return [n, bad]; })()";
    for page in ["index", "incoherent", "meshes", "peers", "paper", "resolution"] {
        browser.open(&url(&format!("{page}.html")));
        let seen = browser.eval(colour_check);
        assert!(seen[0].as_u64() > Some(0) || page == "paper", "{page}.html: no ratio cells ({seen})");
        assert_eq!(seen[1], json!([]), "{page}.html: cells coloured against their interval");
        let headline = browser.eval(
            "(() => { const h = document.querySelector('p.headline'), s = document.querySelector('h2, table.summary');
                return h ? [h.textContent, !s || h.getBoundingClientRect().top < s.getBoundingClientRect().top] : null; })()",
        );
        assert!(
            headline[0]
                .as_str()
                .is_some_and(|t| t.contains("over ") && t.contains("; above 1 = ") && t.contains(" faster)")),
            "{page}.html: {headline}"
        );
        if page != "index" {
            assert_eq!(headline[1], json!(true), "{page}.html: the headline comes before the first section");
        }
        eprintln!("{page}.html: {} ratio cells coloured by their intervals; headline {}", seen[0], headline[0]);
    }
    // The index answers "is ours faster than Embree on ambient-occlusion rays in Munich, by how much, how sure?" on
    // its first screen (1280×900 by default here): the incoherent grid's cell, with its interval.
    browser.open(&url("index.html"));
    let munich = browser.eval(
        "(() => { const t = document.querySelector('section.lead table.matrix'); if (!t) return null;
            const col = Array.from(t.querySelectorAll('thead th')).findIndex(h => h.textContent.includes('ambient-occlusion'));
            const row = Array.from(t.querySelectorAll('tbody tr')).find(r => r.querySelector('th').textContent.includes('munich'));
            if (col < 1 || !row) return null; const cell = row.children[col];
            return [cell.textContent, cell.className, cell.getBoundingClientRect().bottom <= window.innerHeight]; })()",
    );
    assert!(munich[0].as_str().is_some_and(|t| t.contains('[')), "index: no Munich ambient-occlusion cell ({munich})");
    assert_eq!(munich[2], json!(true), "index: the Munich ambient-occlusion cell is below the first screen ({munich})");
    eprintln!("index: Munich ambient occlusion {} ({}) on the first screen", munich[0], munich[1]);
    // A long matrix keeps its header row and label column in view: no inner scroll box, sticky cells.
    browser.open(&url("meshes.html"));
    let sticky = browser.eval(
        "(() => { const t = Array.from(document.querySelectorAll('table.matrix')).pop();
            window.scrollTo(0, t.getBoundingClientRect().top + window.scrollY + 300);
            const h = t.querySelector('thead th'), l = t.querySelector('tbody th');
            return [h.getBoundingClientRect().top, getComputedStyle(h).position, getComputedStyle(l).position,
                    getComputedStyle(t.parentElement).overflowY]; })()",
    );
    assert!(
        sticky[0].as_f64().is_some_and(|top| top.abs() < 2.0),
        "meshes.html: header not in view after a scroll ({sticky})"
    );
    assert_eq!(sticky[1], json!("sticky"), "meshes.html: {sticky}");
    assert_eq!(sticky[2], json!("sticky"), "meshes.html: {sticky}");
    assert_ne!(sticky[3], json!("auto"), "meshes.html: the matrix scrolls in a box of its own ({sticky})");

    // Series tell apart by colour or marker (as in the PNG figures), each series looks the same in every chart of a
    // page, and a category axis (workloads) draws points with intervals, no lines between categories.
    for page in ["meshes", "peers"] {
        browser.open(&url(&format!("{page}.html")));
        let seen = browser.eval(
            "(() => { const looks = {}, same = [], categorical = [];
                for (const f of document.querySelectorAll('figure.chart')) {
                    const spec = JSON.parse(document.getElementById(f.dataset.source).textContent);
                    const charted = {};
                    for (const p of f.querySelectorAll('.pt')) {
                        const look = p.getAttribute('fill') + ' ' + p.dataset.marker;
                        charted[p.dataset.series] = look;
                        (looks[p.dataset.series] = looks[p.dataset.series] || new Set()).add(look);
                    }
                    const names = Object.keys(charted);
                    for (const a of names) for (const b of names) if (a < b && charted[a] === charted[b]) same.push(a + ' = ' + b);
                    if (spec.categorical) categorical.push([f.querySelectorAll('path.line').length, f.querySelectorAll('.pt').length]);
                }
                const wide = ['ours-wide', 'ours-wide-binned'].map(s => looks[s] ? Array.from(looks[s]).join() : null);
                const varying = Object.entries(looks).filter(([, l]) => l.size > 1).map(([s, l]) => s + ': ' + Array.from(l));
                return [same, varying, categorical, wide]; })()",
        );
        assert_eq!(seen[0], json!([]), "{page}.html: series drawn alike on one chart");
        assert_eq!(seen[1], json!([]), "{page}.html: a series drawn differently on two charts");
        if page == "meshes" {
            let categorical = seen[2].as_array().unwrap();
            assert!(!categorical.is_empty(), "meshes.html: no chart over workloads ({seen})");
            for c in categorical {
                assert!(
                    c[0] == json!(0) && c[1].as_u64() > Some(0),
                    "meshes.html: a category chart joins its points ({c})"
                );
            }
            let wide = seen[3].as_array().unwrap();
            assert!(wide[0].is_string() && wide[1].is_string() && wide[0] != wide[1], "meshes.html: {seen}");
        }
        eprintln!("{page}.html: every series one look, told apart on each chart; category charts {}", seen[2]);
    }

    // The head-to-head pages lead with the answer: a ratio matrix coloured by verdict, above their figures.
    for page in ["meshes", "peers"] {
        browser.open(&url(&format!("{page}.html")));
        let seen = browser.eval(
            "(() => { const m = document.querySelector('table.matrix'), f = document.querySelectorAll('figure img, figure.chart');
                if (!m) return null;
                const cells = Array.from(m.querySelectorAll('tbody td')).filter(c => c.textContent.trim() !== '');
                const coloured = cells.filter(c => ['faster', 'slower', 'same'].some(k => c.classList.contains(k))).length;
                const firstFigure = f.length ? f[0].getBoundingClientRect().top : -1;
                return [m.querySelectorAll('tbody tr').length, cells.length, coloured, f.length,
                        m.getBoundingClientRect().top < firstFigure]; })()",
        );
        let [rows, cells, coloured, figures, above] = seen.as_array().map(Vec::as_slice).unwrap_or_default() else {
            panic!("{page}.html: no ratio matrix ({seen})");
        };
        assert!(rows.as_u64() > Some(0) && cells.as_u64() > Some(0) && cells == coloured, "{page}.html: matrix {seen}");
        assert!(figures.as_u64() > Some(0) && *above == json!(true), "{page}.html: figures below the matrix {seen}");
        eprintln!("{page}.html: ratio matrix of {rows} points, {coloured} coloured cells, {figures} figures below it");
    }
}

/// Opens each of `pages` (in `out`) in a browser of its own and checks it: no console errors, no chart title or
/// legend over the plot, a screenshot that is not blank. Returns the slowest load in ms and its page.
fn check_pages(binary: &Path, out: &Path, pages: &[String], tag: &str) -> (f64, String) {
    let mut browser = Browser::start(binary, tag);
    let url = |page: &str| format!("file://{}", out.join(page).display());
    let mut slowest = (0.0, String::new());
    for page in pages {
        browser.open(&url(page));
        let errors = browser.errors();
        assert!(errors.is_empty(), "{page}: {errors:?}");
        let load_ms = browser.eval("performance.getEntriesByType('navigation')[0].loadEventEnd").as_f64().unwrap();
        if load_ms > slowest.0 {
            slowest = (load_ms, page.clone());
        }
        let layout = browser.eval(
            "Array.from(document.querySelectorAll('figure.chart')).flatMap(f => {
                const box = (e) => e.getBoundingClientRect();
                const title = f.querySelector('.chart-title'), legend = f.querySelector('.legend');
                const area = box(f.querySelector('.plot-area'));
                const problems = [];
                if (title.scrollWidth > title.clientWidth + 1 || box(title).right > box(f).right + 1) problems.push('title clipped: ' + title.textContent);
                if (box(title).bottom > area.top) problems.push('title over the plot: ' + title.textContent);
                if (box(legend).top < area.bottom) problems.push('legend over the plot: ' + title.textContent);
                const axis = Array.from(f.querySelectorAll('.axis-label')).map(box);
                for (const tick of Array.from(f.querySelectorAll('.tick')).map(box)) {
                    if (tick.right > area.left + 1 && tick.left < area.left - 1 && tick.bottom <= area.bottom) problems.push('y tick label over the plot: ' + title.textContent);
                    for (const a of axis) if (tick.left < a.right && a.left < tick.right && tick.top < a.bottom && a.top < tick.bottom) problems.push('axis title over a tick label: ' + title.textContent);
                }
                return problems;
            })",
        );
        assert_eq!(layout, json!([]), "{page}");
        let colours = browser.screenshot_colours();
        assert!(colours >= 16, "{page}: screenshot has {colours} colours (blank?)");
    }
    slowest
}
