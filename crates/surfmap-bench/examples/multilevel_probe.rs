//! Probe: energy of the multilevel start map (before the fine-level Newton) for
//! different re-insertion settings.
//! `cargo run --release -p surfmap-bench --example multilevel_probe -- MESH LEVELS COARSE POLISH...`
use surfmap::mesh::decimate::{DecimateOptions, decimate_with};
use surfmap::mesh::io::read_mesh;
use surfmap::mesh::subdivide::subdivide_midpoint;
use surfmap::param::element::rest_triangles;
use surfmap::param::multilevel::prolongate;
use surfmap::param::newton::NewtonSolver;
use surfmap::{Alpha, Disc, FlattenOptions, Multilevel, Start, flatten};

fn single_level(start: Start) -> FlattenOptions {
    match start {
        Start::Auto { .. } => FlattenOptions::default().with_start(Start::Auto {
            multilevel: Multilevel::Never,
        }),
        given => FlattenOptions::default().with_start(given),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let levels: usize = args[1].parse().unwrap();
    let coarse_vertices: usize = args[2].parse().unwrap();
    let mut mesh = read_mesh(std::path::Path::new(&args[0])).unwrap().mesh;
    for _ in 0..levels {
        mesh = subdivide_midpoint(&mesh);
    }
    let disc = Disc::new(&mesh).unwrap();
    let t = std::time::Instant::now();
    let dec = decimate_with(
        &mesh.positions,
        &disc,
        &DecimateOptions {
            target_vertices: coarse_vertices,
            ..Default::default()
        },
    )
    .unwrap();
    let (coarse, orig) = dec.coarse_mesh(&mesh);
    println!("decimate {:.2} s", t.elapsed().as_secs_f64());
    let flat = flatten(&coarse, &single_level(Start::default())).unwrap();
    let scale = mesh.area().sqrt();
    let pos: Vec<[f64; 3]> = mesh
        .positions
        .iter()
        .map(|p| p.map(|x| x / scale))
        .collect();
    let rest = rest_triangles(&pos, &mesh.triangles).unwrap();
    let energy = NewtonSolver::energy_of(&rest, &mesh.triangles);
    println!("coarse E {:.6}", flat.energy);
    let sweeps: usize = std::env::var("SWEEPS").map_or(0, |s| s.parse().unwrap());
    for polish in args[3..].iter().map(|s| s.parse::<usize>().unwrap()) {
        let mut uv = vec![[f64::NAN; 2]; mesh.positions.len()];
        for (c, &v) in orig.iter().enumerate() {
            uv[v as usize] = flat.uvs[c];
        }
        let t = std::time::Instant::now();
        let stats = prolongate(
            &mesh.positions,
            &dec,
            disc.boundary(),
            &mut uv,
            &Alpha::balanced(),
            polish,
            sweeps,
        )
        .unwrap();
        let el = t.elapsed().as_secs_f64();
        let uvn: Vec<[f64; 2]> = uv.iter().map(|p| [p[0] / scale, p[1] / scale]).collect();
        println!(
            "polish {polish} sweeps {sweeps}: E {:.6}, {:.2} s, {:?}",
            energy(&uvn, &Alpha::balanced()),
            el,
            stats
        );
        if std::env::var("RUN_FINE").is_ok() {
            let t = std::time::Instant::now();
            let f = flatten(&mesh, &single_level(Start::Given(uv))).unwrap();
            println!(
                "   fine: {} iterations, E {:.6}, {:.2} s",
                f.iterations,
                f.energy,
                t.elapsed().as_secs_f64()
            );
            let steps: Vec<String> = f.log.iter().map(|l| format!("{:.2}", l.step)).collect();
            println!("   steps {}", steps.join(" "));
        }
    }
}
