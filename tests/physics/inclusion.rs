//! The material with a lump: read from the shipped files and checked, assembled element by element
//! (an element the lump's surface cuts integrated by sub-cells), and felt by the converged
//! continuum probe reference as an independent measurement says.

use tissue_sim::mechanics::material::Material;
use tissue_sim::validate::continuum::{DEFAULT_TOLERANCE, Press, press_force};

fn shipped(name: &str) -> Material {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/examples").join(name);
    Material::from_file(&path).expect("a shipped lump")
}

#[test]
fn the_shipped_lumps_read_as_written() {
    let five = shipped("lump_5x_r8.toml");
    let a = Material::object_a();
    assert_eq!(five.inclusions.len(), 1);
    let lump = &five.inclusions[0];
    assert_eq!((lump.centre, lump.radius), ([0.05, 0.05, 0.082], 0.008));
    assert!((lump.stiffness - a.stiffness * 5.0).abs().max() < 1e-9 * a.stiffness.abs().max());
    assert_eq!(five.stiffness_at([0.05, 0.05, 0.089]), &lump.stiffness);
    assert_eq!(five.stiffness_at([0.05, 0.05, 0.095]), &five.stiffness);
    // The key tells the lumps apart, and the background alone from either.
    let three = shipped("lump_3x_r5.toml");
    assert_eq!(three.inclusions[0].radius, 0.005);
    assert!(five.key() != three.key() && five.key()[..36] == three.key()[..36] && a.key().len() == 36);
    assert!(five.require_homogeneous("this").is_err() && a.require_homogeneous("this").is_ok());
}

/// Object A with a lump 5 times stiffer, 8 mm in radius, its top 12 mm under the top face: the
/// 15 mm probe pressed 4 mm above it. Measured outside the project on a linear-elastic continuum
/// (graded hex8, 3 mm at the contact): about 6 % more force than without the lump. Away from it
/// (35 mm to the side), no change to speak of.
#[test]
fn the_continuum_feels_a_lump_under_the_probe() {
    let a = Material::object_a();
    let mut lump = a.clone();
    lump.inclusions.push(tissue_sim::mechanics::inclusion::Inclusion {
        centre: [0.05, 0.05, 0.08],
        radius: 0.008,
        stiffness: a.stiffness * 5.0,
    });
    let force = |m: &Material, at: [f64; 3]| {
        press_force(m, &Press::normal(at, 0.015, 0.004), DEFAULT_TOLERANCE, &mut |_| {}).expect("converges").force_n
    };
    let over = force(&lump, [0.05, 0.05, 0.1]) / force(&a, [0.05, 0.05, 0.1]) - 1.0;
    let away = force(&lump, [0.05, 0.015, 0.1]) / force(&a, [0.05, 0.015, 0.1]) - 1.0;
    eprintln!("over the lump {:+.2} %, 35 mm away {:+.2} %", 100.0 * over, 100.0 * away);
    assert!((0.04..0.09).contains(&over), "over the lump: {:+.2} %", 100.0 * over);
    assert!(away.abs() < 0.01, "away from the lump: {:+.2} %", 100.0 * away);
}
