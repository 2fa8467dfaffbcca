//! `surfmap view PATH -o page.html`: one self-contained interactive HTML page of a
//! flattening, a match folder, a `.glb` morph or rig, or a batch or registration folder
//! ([`surfmap::view`]); `--serve` serves it on 127.0.0.1 instead of (or as well as)
//! leaving it in a file, and opens nothing by itself.

use std::io::{BufRead, BufReader, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use surfmap::view::{PageWritten, ViewInput, ViewOptions, write_page};

#[derive(clap::Args)]
pub struct Args {
    /// What to view: a mesh (flattened: OBJ with `vt`), a match folder, a `.glb` morph
    /// or rig, or a folder with summary.csv (a batch) or summary.json (a registration).
    pub path: PathBuf,
    /// The page to write (HTML). A batch or registration folder also gets one page per
    /// item in OUT_items/ beside it. Optional with --serve (then a temporary folder).
    #[arg(short, long, required_unless_present = "serve")]
    pub output: Option<PathBuf>,
    /// A flattening's report (default: MESH.json beside the mesh, when it exists).
    #[arg(long, value_name = "R.json")]
    pub report: Option<PathBuf>,
    /// A match's surface A (default: the one match.json names).
    #[arg(long, value_name = "A")]
    pub a: Option<PathBuf>,
    /// A match's surface B (default: the one match.json names).
    #[arg(long, value_name = "B")]
    pub b: Option<PathBuf>,
    /// A match's landmarks, shown with their names: {"names": [...], "A": [ids], "B": [ids]}.
    #[arg(long, value_name = "L.json")]
    pub landmarks: Option<PathBuf>,
    /// Serve the page on 127.0.0.1 (until interrupted) and print its address; nothing is
    /// opened.
    #[arg(long)]
    pub serve: bool,
    /// The port for --serve (default: a free one).
    #[arg(long, requires = "serve")]
    pub port: Option<u16>,
    /// Print nothing but errors (and the address with --serve).
    #[arg(short, long)]
    pub quiet: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let options = ViewOptions {
        report: args.report.clone(),
        a: args.a.clone(),
        b: args.b.clone(),
        landmarks: args.landmarks.clone(),
    };
    let input = ViewInput::detect(&args.path, &options)?;
    if args.report.is_some() && !matches!(input, ViewInput::Flattening { .. }) {
        bail!(
            "--report is a flattening's report; {} is not a mesh",
            args.path.display()
        );
    }
    if (args.a.is_some() || args.b.is_some() || args.landmarks.is_some())
        && !matches!(input, ViewInput::Match { .. })
    {
        bail!(
            "--a, --b and --landmarks go with a match folder; {} is not one",
            args.path.display()
        );
    }
    let output = match &args.output {
        Some(o) => o.clone(),
        None => {
            let dir = std::env::temp_dir().join(format!("surfmap-view-{}", std::process::id()));
            std::fs::create_dir_all(&dir)
                .with_context(|| format!("cannot create {}", dir.display()))?;
            dir.join("view.html")
        }
    };
    if output.is_dir() {
        bail!(
            "-o {} is a folder; name the page to write (e.g. -o page.html)",
            output.display()
        );
    }
    let written = write_page(&input, &output)?;
    if !args.quiet {
        describe(&written);
    }
    if args.serve {
        serve(&written, args.port)?;
    }
    Ok(())
}

fn describe(w: &PageWritten) {
    outln!(
        "wrote {} ({} page, {:.1} MB, {} triangles)",
        w.path.display(),
        w.kind.name(),
        w.bytes as f64 / 1e6,
        w.triangles
    );
    if !w.items.is_empty() {
        let dir = w.items[0].path.parent().unwrap_or(Path::new("."));
        outln!("  and {} item pages in {}", w.items.len(), dir.display());
    }
    for n in &w.notes {
        eprintln!("note: {n}");
    }
}

/// Serves the page (at `/`) and a table's item pages (at their relative paths) on
/// 127.0.0.1, one request at a time, until the process is stopped.
fn serve(written: &PageWritten, port: Option<u16>) -> anyhow::Result<()> {
    let listener = TcpListener::bind(("127.0.0.1", port.unwrap_or(0))).with_context(|| {
        format!(
            "cannot listen on 127.0.0.1:{} (is the port taken? choose another with --port, or leave it out for a free one)",
            port.unwrap_or(0)
        )
    })?;
    let address = listener.local_addr()?;
    let root = written
        .path
        .parent()
        .unwrap_or(Path::new("."))
        .to_path_buf();
    let mut files: Vec<(String, PathBuf)> = vec![("/".into(), written.path.clone())];
    for item in &written.items {
        if let Ok(rel) = item.path.strip_prefix(&root) {
            let url = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy())
                .collect::<Vec<_>>()
                .join("/");
            files.push((format!("/{url}"), item.path.clone()));
        }
    }
    outln!(
        "serving {} at http://{address}/ (Ctrl-C stops)",
        written.path.display()
    );
    for stream in listener.incoming() {
        match stream {
            Ok(s) => {
                if let Err(e) = answer(s, &files) {
                    eprintln!("note: a request failed: {e}");
                }
            }
            Err(e) => eprintln!("note: a connection failed: {e}"),
        }
    }
    Ok(())
}

/// Reads one HTTP request and answers it: a known page (200), anything else 404, a
/// method other than GET or HEAD 405.
fn answer(stream: TcpStream, files: &[(String, PathBuf)]) -> std::io::Result<()> {
    stream.set_read_timeout(Some(std::time::Duration::from_secs(10)))?;
    let mut reader = BufReader::new(stream.try_clone()?);
    let mut request = String::new();
    reader.read_line(&mut request)?;
    // The headers, up to the empty line (ignored).
    let mut line = String::new();
    while reader.read_line(&mut line)? > 2 && line.len() < 64 * 1024 {
        line.clear();
    }
    let mut parts = request.split_whitespace();
    let method = parts.next().unwrap_or("");
    let target = parts.next().unwrap_or("/");
    let path = target.split(['?', '#']).next().unwrap_or("/");
    let (status, body, kind): (&str, Vec<u8>, &str) = if method != "GET" && method != "HEAD" {
        (
            "405 Method Not Allowed",
            b"only GET and HEAD\n".to_vec(),
            "text/plain",
        )
    } else {
        match files.iter().find(|(url, _)| url == path) {
            Some((_, file)) => match std::fs::read(file) {
                Ok(bytes) => ("200 OK", bytes, "text/html; charset=utf-8"),
                Err(e) => (
                    "500 Internal Server Error",
                    format!("{e}\n").into_bytes(),
                    "text/plain",
                ),
            },
            None => ("404 Not Found", b"not found\n".to_vec(), "text/plain"),
        }
    };
    let mut out = stream;
    write!(
        out,
        "HTTP/1.1 {status}\r\nContent-Type: {kind}\r\nContent-Length: {}\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n",
        body.len()
    )?;
    if method != "HEAD" {
        out.write_all(&body)?;
    }
    out.flush()
}
