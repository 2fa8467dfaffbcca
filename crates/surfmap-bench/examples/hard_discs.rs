//! Hard discs (issue 12): Newton iterations and time of the default flattening on the
//! cut closed meshes, the higher-genus ones and the discs with holes opened by seams,
//! every one under 20k faces in `../shared/data`.
//!
//! `cargo run --release -p surfmap-bench --example hard_discs [-- --repeat 3] [-- --log] [-- MESH[:cut]...]`
//!
//! `MESH:cut` opens the holes with seams (`--cut-holes`) instead of filling them.
//! `octopus` is the generated disc with long thin arms ([`surfmap::mesh::generate::octopus_disc`],
//! default shape: tubes), `octopus:A,W,L,DOME` one of another shape (arms, tube
//! circumference and length in quads, dome height), `octopus:A,W,L,DOME,TWIST` one with
//! flat arms (base width, twist); the default list ends with it. Per
//! mesh: what was done (plan), whether the boundary barrier was needed, the Newton
//! iterations of the returned solve (the barrier solve when there was one), the
//! iterations of all solves together, the energy, the guarantee, and the median wall
//! and CPU time of the whole `flatten` call (CPU: all threads of the process, from
//! `/proc/self/task/*/schedstat`, so a shared machine's load shows in the wall column
//! only). `--log` prints every iteration of the last run's returned solve, `--log-all`
//! every iteration of every solve of every run as it happens (iteration, stage, energy,
//! decrement, step, flip-free bound; on stderr); `--bijective-off` solves
//! without the boundary barrier (`Bijective::Off`); `--uncut` never cuts the disc
//! (`Cut::Never`: one UV per vertex, as `match` and Python's default need);
//! `--multilevel` forces the multilevel start (`Multilevel::Always`); `--save DIR` writes
//! each mesh there as `NAME.obj` (for the generated ones: to give them to peers).
//! `coarse`: Newton iterations on the multilevel start's coarse level (0 without one;
//! not in `all`); `elastic`: the energy per unit area without the boundary barrier
//! (`energy` includes it after a barrier solve).

use std::path::PathBuf;
use std::time::Instant;
use surfmap::{FlattenOptions, flatten_with_progress, read_mesh};

/// CPU time of all threads of this process so far, seconds (0 where unavailable).
fn cpu_seconds() -> f64 {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
        return 0.0;
    };
    tasks
        .flatten()
        .filter_map(|t| std::fs::read_to_string(t.path().join("schedstat")).ok())
        .filter_map(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .sum::<f64>()
        * 1e-9
}

/// The generated disc named by `path` (`octopus` or `octopus:A,W,L,DOME[,TWIST]`).
fn octopus(path: &std::path::Path) -> Option<surfmap::TriMesh> {
    use surfmap::mesh::generate::{Octopus, octopus_disc};
    let name = path.to_str()?;
    let rest = name.strip_prefix("octopus")?;
    let mut shape = Octopus::default();
    if let Some(list) = rest.strip_prefix(':') {
        let v: Vec<f64> = list
            .split(',')
            .map(|x| x.parse().expect("number"))
            .collect();
        assert!(matches!(v.len(), 4 | 5), "octopus:A,W,L,DOME[,TWIST]");
        (shape.arms, shape.width, shape.length) = (v[0] as usize, v[1] as usize, v[2] as usize);
        shape.dome = v[3];
        if let Some(&twist) = v.get(4) {
            (shape.twist, shape.tube) = (twist, false);
        }
    } else if !rest.is_empty() {
        return None;
    }
    Some(octopus_disc(&shape))
}

/// The elastic energy per unit area of the returned map (without the boundary barrier,
/// which [`surfmap::Flattening::energy`] includes after a barrier solve), on the solved
/// disc's corners: comparable between runs whose barriers differ.
fn elastic_energy(
    mesh: &surfmap::TriMesh,
    r: &surfmap::Flattening,
    energy: &surfmap::Energy,
) -> f64 {
    use surfmap::param::element::{energy as element_energy, rest_triangles};
    let (positions, scale) = mesh.unit_area_positions();
    let Ok(rest) = rest_triangles(&positions, &mesh.triangles) else {
        return f64::NAN;
    };
    let energy = energy.without_continuation();
    r.corner_uvs(&mesh.triangles)
        .iter()
        .zip(&rest)
        .map(|(c, rest)| element_energy(rest, &c.map(|p| [p[0] / scale, p[1] / scale]), &energy))
        .sum()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut repeat = 3;
    if let Some(i) = args.iter().position(|a| a == "--repeat") {
        repeat = args[i + 1].parse().expect("--repeat N");
        args.drain(i..i + 2);
    }
    let print_log = args.iter().any(|a| a == "--log");
    let print_all = args.iter().any(|a| a == "--log-all");
    let bijective_off = args.iter().any(|a| a == "--bijective-off");
    let uncut = args.iter().any(|a| a == "--uncut");
    let multilevel = args.iter().any(|a| a == "--multilevel");
    args.retain(|a| {
        !matches!(
            a.as_str(),
            "--log" | "--log-all" | "--bijective-off" | "--uncut" | "--multilevel"
        )
    });
    let mut coarse_vertices = None;
    if let Some(i) = args.iter().position(|a| a == "--coarse-vertices") {
        coarse_vertices = Some(args[i + 1].parse::<usize>().expect("--coarse-vertices N"));
        args.drain(i..i + 2);
    }
    let mut save = None;
    if let Some(i) = args.iter().position(|a| a == "--save") {
        save = Some(PathBuf::from(&args[i + 1]));
        args.drain(i..i + 2);
    }
    let meshes: Vec<(PathBuf, bool)> = if args.is_empty() {
        let Some(data) = surfmap::testing::shared_data() else {
            eprintln!("no ../shared/data: give meshes on the command line");
            return;
        };
        [
            ("sphere.obj", false),
            ("bunny.off", false),
            ("max_planck.obj", false),
            ("punctured_torus.obj", false),
            ("three_holes.off", false),
            ("elephant_holes.off", false),
            ("halftunnel.off", true),
            ("holes.off", true),
            ("faces/head_cgal.off", true),
            ("faces/ict/ict_neutral.obj", true),
        ]
        .into_iter()
        .map(|(m, cut)| (data.join(m), cut))
        .chain([(PathBuf::from("octopus"), false)])
        .collect()
    } else {
        args.iter()
            .map(|a| match a.strip_suffix(":cut") {
                Some(m) => (PathBuf::from(m), true),
                None => (PathBuf::from(a), false),
            })
            .collect()
    };
    println!(
        "{:<22} {:>6} {:<44} {:>7} {:>5} {:>5} {:>6} {:>10} {:>10} {:>9} {:>8} {:>8}",
        "mesh",
        "F",
        "plan",
        "barrier",
        "iters",
        "all",
        "coarse",
        "energy",
        "elastic",
        "guarantee",
        "wall_s",
        "cpu_s"
    );
    for (path, cut_holes) in &meshes {
        let mesh = match octopus(path) {
            Some(m) => Ok(m),
            None => read_mesh(path).map(|m| m.mesh),
        };
        let mesh = match mesh {
            Ok(m) => m,
            Err(e) => {
                eprintln!("{}: {e}", path.display());
                continue;
            }
        };
        if let (Some(dir), Some(name)) = (&save, path.file_name().and_then(|n| n.to_str())) {
            let file = dir.join(format!("{}.obj", name.replace([':', ','], "_")));
            surfmap::write_mesh(&file, &mesh).expect("written");
        }
        let mut options = FlattenOptions::default().with_fill_holes(!cut_holes);
        if bijective_off {
            options = options.with_bijective(surfmap::Bijective::Off);
        }
        if uncut {
            options = options.with_cut(surfmap::Cut::Never);
        }
        if multilevel {
            options = options.with_start(surfmap::Start::Auto {
                multilevel: surfmap::Multilevel::Always(surfmap::CoarseLevel {
                    vertices: coarse_vertices,
                    ..Default::default()
                }),
            });
        }
        let (mut walls, mut cpus) = (Vec::new(), Vec::new());
        let mut last = None;
        for _ in 0..repeat.max(1) {
            let mut all = 0usize;
            let (c0, t0) = (cpu_seconds(), Instant::now());
            let result = flatten_with_progress(&mesh, &options, &mut |l| {
                all += usize::from(l.iteration > 0);
                if print_all {
                    eprintln!(
                        "{:3} {:2} {:14.6} {:10.3e} {:10.3e} {:10.3e}",
                        l.iteration,
                        l.stage,
                        l.energy,
                        l.newton_decrement,
                        l.step,
                        l.flip_free_step
                    );
                }
            });
            walls.push(t0.elapsed().as_secs_f64());
            cpus.push(cpu_seconds() - c0);
            match result {
                Ok(r) => last = Some((r, all)),
                Err(e) => {
                    eprintln!("{}: {e}", path.display());
                    break;
                }
            }
        }
        let Some((r, all)) = last else { continue };
        let name = path
            .file_name()
            .unwrap()
            .to_string_lossy()
            .replace("octopus:", "oct:");
        let name = if *cut_holes {
            format!("{name} (cut)")
        } else {
            name.to_string()
        };
        let coarse = r.multilevel.as_ref().map_or(0, |m| m.coarse_iterations);
        println!(
            "{:<22} {:>6} {:<44} {:>7} {:>5} {:>5} {:>6} {:>10.6} {:>10.6} {:>9} {:>8.3} {:>8.3}",
            name,
            mesh.triangles.len(),
            r.plan.describe().chars().take(44).collect::<String>(),
            if r.barrier { "yes" } else { "no" },
            r.iterations,
            all,
            coarse,
            r.energy,
            elastic_energy(&mesh, &r, &options.energy),
            format!("{:?}", r.guarantee),
            median(walls),
            median(cpus),
        );
        if print_log {
            println!("  start: {}", r.start_description());
            println!("  {:?}", r.newton_timings);
            println!(
                "  {:>4} {:>5} {:>14} {:>10} {:>10} {:>9} {:>10}",
                "it", "stage", "energy", "|grad|", "decrement", "step", "step_max"
            );
            for l in &r.log {
                println!(
                    "  {:>4} {:>5} {:>14.8} {:>10.3e} {:>10.3e} {:>9.3e} {:>10.3e}",
                    l.iteration,
                    l.stage,
                    l.energy,
                    l.gradient_norm,
                    l.newton_decrement,
                    l.step,
                    l.flip_free_step
                );
            }
        }
    }
}
