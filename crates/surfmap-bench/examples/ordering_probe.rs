//! One vertex ordering for all per-vertex systems (AMD or METIS nested dissection on the
//! vertex graph) versus AMD on each system: ordering time, rest of the symbolic phase,
//! fill of `L`, numeric factorization time.
//! `cargo run --release -p surfmap-bench --example ordering_probe -- MESH [LEVELS]`
use std::time::Instant;
use surfmap::linsolve::{Ordering, SpdSystem, Unknowns, VertexOrdering};

fn median(mut t: Vec<f64>) -> f64 {
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

/// Symbolic time, nnz(L), median numeric time of a diagonally dominant matrix on `entries`.
fn measure(dim: usize, entries: &[(u32, u32)], ordering: &Ordering) -> (f64, usize, f64, f64) {
    let symbolic = median(
        (0..5)
            .map(|_| {
                let t = Instant::now();
                let _ = SpdSystem::with_ordering(dim, entries, ordering).unwrap();
                t.elapsed().as_secs_f64()
            })
            .collect(),
    );
    let (mut sys, slots) = SpdSystem::with_ordering(dim, entries, ordering).unwrap();
    let v = sys.values_mut();
    for &s in &slots {
        v[s as usize] -= 1.0;
    }
    surfmap::testing::make_diagonally_dominant(&mut sys);
    let t = Instant::now();
    sys.factorize().unwrap();
    let first = t.elapsed().as_secs_f64();
    let numeric = min((0..9)
        .map(|_| {
            let t = Instant::now();
            sys.factorize().unwrap();
            t.elapsed().as_secs_f64()
        })
        .collect());
    (symbolic, sys.nnz_factor(), numeric, first)
}

fn min(t: Vec<f64>) -> f64 {
    t.into_iter().fold(f64::INFINITY, f64::min)
}

fn time<T>(f: impl Fn() -> T) -> (f64, T) {
    let times: Vec<f64> = (0..5)
        .map(|_| {
            let t = Instant::now();
            let _ = f();
            t.elapsed().as_secs_f64()
        })
        .collect();
    (median(times), f())
}

fn main() {
    let path = std::env::args().nth(1).expect("MESH");
    let mut mesh = surfmap::mesh::io::read_mesh(path.as_ref())
        .expect("readable")
        .mesh;
    // Optional: subdivide (midpoint 1 → 4) this many times first.
    let levels: usize = std::env::args()
        .nth(2)
        .map_or(0, |s| s.parse().expect("LEVELS"));
    for _ in 0..levels {
        mesh = surfmap::mesh::subdivide::subdivide_midpoint(&mesh);
    }
    let nv = mesh.positions.len();
    // Pins as in a flattening: vertex 0 (both coordinates; alone in the Laplacian),
    // the v coordinate of the last vertex.
    let dof1 = Unknowns::new(nv, [0]);
    let dof2 = Unknowns::new(2 * nv, [0, 1, 2 * nv - 1]);
    let (mut lap, mut blk) = (Vec::new(), Vec::new());
    for t in &mesh.triangles {
        for i in 0..3 {
            for j in 0..=i {
                let (a, b) = (t[i] as usize, t[j] as usize);
                if let (Some(p), Some(q)) = (dof1.get(a), dof1.get(b)) {
                    lap.push((p, q));
                }
                for ca in 0..2 {
                    for cb in 0..2 {
                        if let (Some(p), Some(q)) = (dof2.get(2 * a + ca), dof2.get(2 * b + cb)) {
                            blk.push((p, q));
                        }
                    }
                }
            }
        }
    }
    // LSCM: u–u and v–v couplings on every edge, u–v only along the boundary; vertex 0
    // and the last vertex pinned (both coordinates).
    let disc = surfmap::Disc::new(&mesh).expect("a disc");
    let boundary = disc.boundary();
    let dof_lscm = Unknowns::new(2 * nv, [0, 1, 2 * nv - 2, 2 * nv - 1]);
    let m = dof_lscm.count();
    let mut lscm = Vec::new();
    let mut push = |a: u32, ca: usize, b: u32, cb: usize| {
        let (p, q) = (
            dof_lscm.get(2 * a as usize + ca),
            dof_lscm.get(2 * b as usize + cb),
        );
        if let (Some(p), Some(q)) = (p, q) {
            lscm.push((p, q));
        }
    };
    for t in &mesh.triangles {
        for k in 0..3 {
            let (i, j) = (t[k], t[(k + 1) % 3]);
            for c in 0..2 {
                push(i, c, i, c);
                push(j, c, j, c);
                push(i, c, j, c);
            }
        }
    }
    for k in 0..boundary.len() {
        let (i, j) = (boundary[k], boundary[(k + 1) % boundary.len()]);
        push(i, 0, j, 1);
        push(j, 0, i, 1);
    }
    let (t_vertex, vo) = time(|| VertexOrdering::of_triangles(nv, &mesh.triangles).unwrap());
    let (t_nd, nd) = time(|| VertexOrdering::nested_dissection(nv, &mesh.triangles).unwrap());
    println!("vertex nested dissection (METIS): {t_nd:.4} s");
    // The vertex order implied by AMD on the LSCM system: each vertex where its first
    // unknown is eliminated (pinned vertices last).
    let lscm_amd = VertexOrdering::of_graph(m, &lscm).unwrap();
    let mut vertex_of = vec![0u32; m];
    for d in 0..dof_lscm.len() {
        if let Some(u) = dof_lscm.get(d) {
            vertex_of[u as usize] = (d / 2) as u32;
        }
    }
    let mut seen = vec![false; nv];
    let mut contracted = Vec::with_capacity(nv);
    for &u in lscm_amd.order() {
        let v = vertex_of[u as usize];
        if !std::mem::replace(&mut seen[v as usize], true) {
            contracted.push(v);
        }
    }
    for v in 0..nv as u32 {
        if !seen[v as usize] {
            contracted.push(v);
        }
    }
    let from_lscm = VertexOrdering::from_order(contracted).unwrap();
    println!("vertex AMD (n = {nv}): {:.4} s", t_vertex);
    for (name, per, dof, entries) in [
        ("laplacian", 1, &dof1, &lap),
        ("2-dof", 2, &dof2, &blk),
        ("lscm", 2, &dof_lscm, &lscm),
    ] {
        let dim = dof.count();
        let (t_amd, own) = time(|| {
            VertexOrdering::of_graph(dim, entries)
                .unwrap()
                .order()
                .to_vec()
        });
        let (t_expand, expanded) = time(|| vo.expand(per, dof).unwrap());
        println!("{name} n {dim}: AMD alone {t_amd:.4} s, expand {t_expand:.5} s");
        for (label, ord) in [
            ("amd (in faer)", Ordering::Amd),
            ("own amd, custom", Ordering::Custom(own)),
            ("vertex expanded", expanded),
            ("vertex METIS nd", nd.expand(per, dof).unwrap()),
            ("from lscm amd", from_lscm.expand(per, dof).unwrap()),
        ] {
            let (s, nnz, num, first) = measure(dim, entries, &ord);
            println!(
                "  {label:<16} symbolic {s:.4} s  nnz(L) {nnz:>9}  numeric min {num:.4} s, first {first:.4} s"
            );
        }
    }
    for _ in 0..3 {
        let t = Instant::now();
        surfmap::param::lscm::lscm(&mesh.positions, &disc).unwrap();
        println!("lscm() {:.4} s", t.elapsed().as_secs_f64());
    }
}
