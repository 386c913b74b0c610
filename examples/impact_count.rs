use ricochet::impact::{self, ContactVelocity, ImpactMatrix, ImpactProblem, Law};
use std::hint::black_box;
fn main() {
    let law: Law = std::env::args().nth(1).unwrap().parse().unwrap();
    let n: usize = std::env::args().nth(2).unwrap().parse().unwrap();
    let pb = ImpactProblem::new(
        ImpactMatrix::new(0.33652, -0.50710, 0.81345),
        ContactVelocity::new(-0.2684, 0.5343),
        0.5,
        0.2,
    );
    let mut acc = 0.0;
    let mut best = f64::INFINITY;
    for _ in 0..7 {
        let t0 = std::time::Instant::now();
        for _ in 0..n {
            acc += impact::solve(black_box(law), black_box(&pb))
                .unwrap()
                .impulse
                .n;
        }
        best = best.min(t0.elapsed().as_secs_f64() / n as f64 * 1e9);
    }
    println!("{law} {best:.1} ns/call ({acc})");
}
