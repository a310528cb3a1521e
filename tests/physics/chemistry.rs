//! The emission chemistry against NCAR GLOW 4.0.4 driven by GLOW's own
//! ionization rate and densities (the fixture `tests/data/glow_chemistry.csv`
//! from `tools/reference/glow_tables.py`: E0 = 1, 3, 10 keV, Q = 1 and 10 erg cm^-2
//! s^-1, Maxwellian, 67 N 20 E 2020-01-15 00 UT, nightglow subtracted).

use aurora::physics::atmosphere::Atmosphere;
use aurora::physics::chemistry::{solve, Air, Ambient};

struct Row {
    e0: f64,
    qf: f64,
    z: f64,
    q: f64,
    n2: f64,
    o2: f64,
    o: f64,
    no: f64,
    n4s: f64,
    tn: f64,
    te: f64,
    ver: [f64; 3],
}

fn fixture() -> Vec<Row> {
    include_str!("../data/glow_chemistry.csv")
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with('e'))
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            Row {
                e0: v[0],
                qf: v[1],
                z: v[2],
                q: v[3],
                n2: v[4],
                o2: v[5],
                o: v[6],
                no: v[7],
                n4s: v[8],
                tn: v[9],
                te: v[10],
                ver: [v[12], v[13], v[14]],
            }
        })
        .collect()
}

/// Column (trapezoid over GLOW's grid, per km) of `f` over the rows.
fn column(rows: &[&Row], f: impl Fn(&Row) -> f64) -> f64 {
    rows.windows(2).map(|w| 0.5 * (f(w[0]) + f(w[1])) * (w[1].z - w[0].z)).sum()
}

#[test]
fn columns_match_glow_driven_by_its_own_ionization() {
    let all = fixture();
    let atm = Atmosphere::nrlmsis21();
    let amb = atm.ambient();
    let mut report = String::new();
    let mut worst = [0.0f64; 3];
    let (mut worst_shape, mut worst_centroid) = (0.0f64, 0.0f64);
    for (e0, qf) in [(1.0, 1.0), (1.0, 10.0), (3.0, 1.0), (3.0, 10.0), (10.0, 1.0), (10.0, 10.0)] {
        let rows: Vec<&Row> = all.iter().filter(|r| r.e0 == e0 && r.qf == qf && r.z <= 500.0).collect();
        let ours: Vec<[f64; 3]> = rows
            .iter()
            .map(|r| {
                let a = amb.at(r.z);
                let air = Air { h_km: r.z, n2: r.n2, o2: r.o2, o: r.o, ambient: Ambient { tn: r.tn, te: r.te, no: r.no, n4s: r.n4s, ..a } };
                let e = solve(r.q.max(1e-6), &air);
                [e.per_ion_pair[3] * r.q, e.per_ion_pair[0] * r.q, e.per_ion_pair[1] * r.q]
            })
            .collect();
        let mut got = [0.0; 3];
        let mut want = [0.0; 3];
        for k in 0..3 {
            let idx: Vec<usize> = (0..rows.len()).collect();
            got[k] = idx.windows(2).map(|w| 0.5 * (ours[w[0]][k] + ours[w[1]][k]) * (rows[w[1]].z - rows[w[0]].z)).sum();
            want[k] = column(&rows, |r| r.ver[k]);
            worst[k] = worst[k].max((got[k] / want[k] - 1.0).abs());
        }
        // 557.7 nm shape: L1 distance of the profiles normalised to unit
        // column; 630.0 nm: column-weighted centroid altitude.
        let dz: Vec<f64> = (0..rows.len()).map(|i| 0.5 * (rows[(i + 1).min(rows.len() - 1)].z - rows[i.saturating_sub(1)].z)).collect();
        let l1: f64 = (0..rows.len()).map(|i| (ours[i][1] / got[1] - rows[i].ver[1] / want[1]).abs() * dz[i]).sum();
        let centroid = |f: &dyn Fn(usize) -> f64| {
            let (a, b) = (0..rows.len()).fold((0.0, 0.0), |(a, b), i| (a + f(i) * rows[i].z * dz[i], b + f(i) * dz[i]));
            a / b
        };
        let dc = centroid(&|i| ours[i][2]) - centroid(&|i| rows[i].ver[2]);
        worst_shape = worst_shape.max(l1);
        worst_centroid = worst_centroid.max(dc.abs());
        report += &format!(
            "E0 {e0} Q {qf}: 4278 {:.3} 5577 {:.3} 6300 {:.3} (ours/GLOW); 5577 L1 {l1:.3}; 6300 centroid {dc:+.1} km\n",
            got[0] / want[0],
            got[1] / want[1],
            got[2] / want[2]
        );
    }
    println!("{report}");
    // The whole pipeline's targets (tests/python/test_glow.py) are 15 %
    // (427.8), 15 % (557.7/427.8), 25-40 % (630.0/427.8), L1 0.2 and
    // 20 km; on GLOW's own ionization the chemistry alone must do much
    // better (measured: within 1 %, 3 %, 8 %, L1 <= 0.05, centroid within
    // 6 km): 5 %, 10 %, 15 %, L1 0.1 and 10 km leave room for rate
    // updates, not for a lost channel (dropping the ion and N(2D)
    // chemistry costs 557.7 nm 12-28 %).
    assert!(worst[0] < 0.05 && worst[1] < 0.10 && worst[2] < 0.15, "{report}");
    assert!(worst_shape < 0.1 && worst_centroid < 10.0, "{report}");
}
