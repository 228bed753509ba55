//! `[friction]`: the friction law of the interface, its defaults and its errors (file, line, key).

mod common;

use common::{error_at, parse, BASE};
use ssvr_core::FrictionLaw;

fn with_friction(table: &str) -> String {
    BASE.replace("[input]", &format!("[friction]\n{table}[input]"))
}

#[test]
fn coulomb_by_default_and_by_name() {
    let s = parse(BASE).unwrap();
    assert_eq!(s.friction, FrictionLaw::Coulomb);
    assert_eq!(s.estimator.friction, FrictionLaw::Coulomb);
    let s = parse(&with_friction("law = \"coulomb\"\n")).unwrap();
    assert_eq!(s.friction, FrictionLaw::Coulomb);
    assert_eq!(s.static_friction_coefficient, 0.2);
}

#[test]
fn velocity_dependent_law_and_its_static_default() {
    let s = parse(&with_friction(
        "law = \"velocity-dependent\"\nmu_slow = 0.12\nrate_s_m = 30.0\n",
    ))
    .unwrap();
    let law = FrictionLaw::VelocityDependent {
        mu_slow: 0.12,
        rate_s_m: 30.0,
    };
    assert_eq!(s.friction, law);
    // μs defaults to μ_slow, and the prior carries the law.
    assert_eq!(s.static_friction_coefficient, 0.12);
    assert_eq!(s.estimator.friction, law);
    assert_eq!(s.estimator.static_friction_coefficient, 0.12);
    // μs between μ_slow and μ_fast is allowed with this law.
    let text = with_friction("law = \"velocity-dependent\"\nmu_slow = 0.12\nrate_s_m = 30.0\n")
        .replace(
            "friction_coefficient = 0.2\n",
            "friction_coefficient = 0.2\nstatic_friction_coefficient = 0.15\n",
        );
    assert_eq!(parse(&text).unwrap().static_friction_coefficient, 0.15);
}

#[test]
fn bad_friction_tables_name_the_key() {
    // Lines: the [friction] header is line 9, its keys from line 10.
    error_at(
        &with_friction("law = \"stribeck\"\n"),
        10,
        &["[friction] law = \"stribeck\"", "\"velocity-dependent\""],
    );
    error_at(
        &with_friction("law = \"velocity-dependent\"\nmu_slow = 0.3\nrate_s_m = 30.0\n"),
        11,
        &["[friction] mu_slow = 0.3 is out of range", "mu_slow <="],
    );
    error_at(
        &with_friction("law = \"velocity-dependent\"\nmu_slow = 0.1\nrate_s_m = -1.0\n"),
        12,
        &["[friction] rate_s_m = -1 is out of range"],
    );
    error_at(
        &with_friction("law = \"velocity-dependent\"\nmu_slow = 0.1\nrate_s_m = nan\n"),
        12,
        &["[friction] rate_s_m must be a finite number"],
    );
    error_at(
        &with_friction("law = \"velocity-dependent\"\nrate_s_m = 30.0\n"),
        9,
        &["[friction] missing key `mu_slow`"],
    );
    error_at(
        &with_friction("law = \"coulomb\"\nmu_slow = 0.1\n"),
        11,
        &["[friction] mu_slow applies to law = \"velocity-dependent\" only"],
    );
    error_at(
        &with_friction("law = \"coulomb\"\nmu = 0.1\n"),
        11,
        &["[friction] unknown key `mu`"],
    );
    // μs below μ_slow.
    let text = with_friction("law = \"velocity-dependent\"\nmu_slow = 0.12\nrate_s_m = 30.0\n")
        .replace(
            "friction_coefficient = 0.2\n",
            "friction_coefficient = 0.2\nstatic_friction_coefficient = 0.1\n",
        );
    error_at(
        &text,
        9,
        &[
            "[structure] static_friction_coefficient = 0.1",
            ">= [friction] mu_slow",
        ],
    );
}

#[test]
fn the_prior_law_can_differ_from_the_interface() {
    let law = "law = \"velocity-dependent\"\nmu_slow = 0.12\nrate_s_m = 30.0\n";
    let text = format!(
        "{}[estimator]\nfriction_coefficient = 0.22\nmu_slow = 0.15\nrate_s_m = 60.0\n",
        with_friction(law)
    );
    let s = parse(&text).unwrap();
    assert_eq!(
        s.friction,
        FrictionLaw::VelocityDependent {
            mu_slow: 0.12,
            rate_s_m: 30.0
        }
    );
    assert_eq!(
        s.estimator.friction,
        FrictionLaw::VelocityDependent {
            mu_slow: 0.15,
            rate_s_m: 60.0
        }
    );
    assert_eq!(s.estimator.params.friction_coefficient, 0.22);
    // The prior's μs: the scene's (0.12) is below the prior's μ_slow: raised to it.
    assert_eq!(s.estimator.static_friction_coefficient, 0.15);
    // Errors name the [estimator] key.
    let bad = format!("{}[estimator]\nmu_slow = 0.3\n", with_friction(law));
    error_at(&bad, 20, &["[estimator] mu_slow = 0.3 is out of range"]);
    let bad = format!("{BASE}[estimator]\nrate_s_m = 3.0\n");
    error_at(
        &bad,
        16,
        &["[estimator] rate_s_m applies to a [friction] law"],
    );
}
