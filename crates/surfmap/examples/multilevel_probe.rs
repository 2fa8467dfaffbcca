//! Probe: how many fine-level Newton iterations remain from an ideal coarse start?
use surfmap::mesh::TriMesh;
use surfmap::mesh::io::read_mesh;
use surfmap::mesh::subdivide::subdivide_midpoint;
use surfmap::param::flatten::{FlattenOptions, flatten};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let levels: usize = args[1].parse().unwrap();
    let coarse_levels: usize = args[2].parse().unwrap();
    let mut mesh = read_mesh(std::path::Path::new(&args[0])).unwrap().mesh;
    for _ in 0..coarse_levels {
        mesh = subdivide_midpoint(&mesh);
    }
    let t = std::time::Instant::now();
    let c = flatten(&mesh, &FlattenOptions::default()).unwrap();
    println!(
        "coarse {} faces: {} its, E {:.6}, {:.2} s",
        mesh.triangles.len(),
        c.iterations,
        c.energy,
        t.elapsed().as_secs_f64()
    );
    let mut uvmesh = TriMesh {
        positions: c.uvs.iter().map(|p| [p[0], p[1], 0.0]).collect(),
        triangles: mesh.triangles.clone(),
        uvs: None,
    };
    for _ in coarse_levels..levels {
        mesh = subdivide_midpoint(&mesh);
        uvmesh = subdivide_midpoint(&uvmesh);
    }
    let uv: Vec<[f64; 2]> = uvmesh.positions.iter().map(|p| [p[0], p[1]]).collect();
    let t = std::time::Instant::now();
    let f = flatten(
        &mesh,
        &FlattenOptions {
            initial_uv: Some(uv),
            warm_start: false,
            ..Default::default()
        },
    )
    .unwrap();
    println!(
        "fine {} faces: {} its, E {:.6}, {:.2} s",
        mesh.triangles.len(),
        f.iterations,
        f.energy,
        t.elapsed().as_secs_f64()
    );
    for l in &f.log {
        println!(
            "{:>3} {:.8} {:.3e} {:.3}",
            l.iteration, l.energy, l.newton_decrement, l.step
        );
    }
    println!("{:?}", f.newton_timings);
}
