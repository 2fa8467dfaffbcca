//! Fill of the Newton system's Cholesky factor versus the scalar Laplacian's, and
//! numeric factorization time, for one mesh (ordering experiments).
//! `cargo run --release -p surfmap-bench --example factor_fill -- MESH`
use std::time::Instant;
use surfmap::linsolve::SpdSystem;

fn main() {
    let path = std::env::args().nth(1).expect("MESH");
    let mesh = surfmap::mesh::io::read_mesh(path.as_ref())
        .expect("readable")
        .mesh;
    let n = mesh.positions.len();
    let mut lap = Vec::new();
    let mut blk = Vec::new();
    for t in &mesh.triangles {
        for i in 0..3 {
            for j in 0..=i {
                let (a, b) = (t[i], t[j]);
                lap.push((a, b));
                for ca in 0..2 {
                    for cb in 0..2 {
                        blk.push((2 * a + ca, 2 * b + cb));
                    }
                }
            }
        }
    }
    for (name, dim, entries) in [("laplacian", n, &lap), ("2-dof", 2 * n, &blk)] {
        let t = Instant::now();
        let (mut sys, slots) = SpdSystem::new(dim, entries).unwrap();
        let symbolic = t.elapsed().as_secs_f64();
        let v = sys.values_mut();
        for &s in &slots {
            v[s as usize] -= 1.0;
        }
        // Make it diagonally dominant: add |row sum| + 1 to every diagonal.
        surfmap::testing::make_diagonally_dominant(&mut sys);
        let mut times = Vec::new();
        for _ in 0..5 {
            let t = Instant::now();
            sys.factorize().unwrap();
            times.push(t.elapsed().as_secs_f64());
        }
        times.sort_by(f64::total_cmp);
        println!(
            "{name:>10}: n {dim:>8}  nnz(A) {:>9}  nnz(L) {:>10}  symbolic {:.4} s  numeric median {:.4} s",
            sys.nnz_lower(),
            sys.nnz_factor(),
            symbolic,
            times[2]
        );
    }
}
