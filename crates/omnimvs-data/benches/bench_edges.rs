#![allow(clippy::unwrap_used, clippy::expect_used)]
//! `snap_edges` (`infer --snap-edges`) on an index map of the paper's grid, 160x640, N = 192:
//! a floor of far values with 40 near boxes whose sides are blended over a pixel, so that
//! several percent of the pixels lie in a band (the bundled cascade leaves about 9 % on things
//! frames).
//!
//! `cargo bench -p omnimvs-data --bench bench_edges`

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use omnimvs_data::edges::snap_edges;

fn scene() -> Vec<f32> {
    let (h, w) = (160usize, 640usize);
    let mut map = vec![20.0f32; h * w];
    for b in 0..40usize {
        let (r0, c0) = ((b * 37) % (h - 24), (b * 151) % w);
        let near = 60.0 + (b % 7) as f32 * 15.0;
        for r in r0..r0 + 20 {
            for dc in 0..24 {
                let c = (c0 + dc) % w;
                // One blended pixel on each side of the box, horizontally.
                let v = if dc == 0 || dc == 23 {
                    (near + 20.0) / 2.0
                } else {
                    near
                };
                map[r * w + c] = map[r * w + c].max(v);
            }
        }
    }
    map
}

fn bench(c: &mut Criterion) {
    let map = scene();
    let mut probe = map.clone();
    let moved = snap_edges(&mut probe, 160, 640, 15.36);
    eprintln!("{moved} of {} pixels moved", map.len());
    c.bench_function("snap_edges_160x640", |b| {
        b.iter(|| {
            let mut m = map.clone();
            black_box(snap_edges(&mut m, 160, 640, black_box(15.36)))
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
