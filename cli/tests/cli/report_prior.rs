//! `imu-ar report --prior-a`: the lattice from a prior next to the plain one, prior.png and
//! `prior_lattice_a`, and the prior's checks (those of `fit`).

use crate::common;

use common::{drift_record, imu_ar, json, misused};

/// With `--prior-a`, report writes prior.png and `prior_lattice_a` and leaves the rest as it
/// is; the lattice from the prior ends where the plain one does. Without it there is neither.
#[test]
fn report_draws_the_lattice_from_a_prior() {
    let file = drift_record("report-prior.csv", "20000");
    let dir = |name: &str| crate::common::temp_path(name);
    let (with, without) = (dir("prior"), dir("no-prior"));
    let f = file.to_str().unwrap();
    let report = |out: &std::path::Path, extra: &[&str]| {
        let mut args = vec![
            "report",
            f,
            "--column",
            "x",
            "--order",
            "2",
            "--lambda",
            "0.999",
            "--rate",
            "100",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        json(&imu_ar(&args))
    };
    let v = report(&with, &["--prior-a", "1.5,-0.7", "--prior-weight", "300"]);
    let png = std::fs::read(with.join("prior.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "prior.png is not a PNG");
    assert!(png.len() > 10_000, "prior.png: {} bytes", png.len());
    let files: Vec<&str> = v["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap())
        .collect();
    assert_eq!(files.len(), 5, "{files:?}");
    assert!(files[4].ends_with("prior.png"), "{files:?}");
    let coefficients = |key: &str, v: &serde_json::Value| -> Vec<f64> {
        let a = v[key].as_array().unwrap_or_else(|| panic!("{key}: {v}"));
        a.iter().map(|c| c.as_f64().unwrap()).collect()
    };
    let (prior, plain) = (
        coefficients("prior_lattice_a", &v),
        coefficients("lattice_a", &v),
    );
    assert_eq!(prior.len(), 2, "{prior:?}");
    // After 20,000 samples at lambda = 0.999 the prior's weight is 300 x 2e-9: both lattices
    // track the same model (a_1 has drifted from 1.5 to 1.0 by then).
    for (p, q) in prior.iter().zip(&plain) {
        assert!((p - q).abs() < 1e-3, "{prior:?} against {plain:?}");
    }
    assert!((plain[0] - 1.0).abs() < 0.1, "{plain:?}");

    // Without --prior-a: four files, no prior.png, no prior_lattice_a, the same comparison.
    let w = report(&without, &[]);
    assert!(!without.join("prior.png").exists());
    assert!(w.get("prior_lattice_a").is_none(), "{w}");
    assert_eq!(w["files"].as_array().unwrap().len(), 4, "{w}");
    for key in [
        "batch_mse",
        "rls_mse",
        "lattice_mse",
        "lattice_a",
        "batch_a",
    ] {
        assert_eq!(v[key], w[key], "{key}");
    }

    // --prior-weight defaults to the delta of the plain lattice.
    let d = report(&with, &["--prior-a", "1.5,-0.7"]);
    assert_eq!(coefficients("prior_lattice_a", &d).len(), 2, "{d}");
    for out in [with, without] {
        std::fs::remove_dir_all(out).unwrap();
    }
    std::fs::remove_file(file).unwrap();
}

/// `report` refuses a prior as `fit` does, before it creates `--out`.
#[test]
fn report_refuses_a_bad_prior() {
    let file = drift_record("report-bad-prior.csv", "2000");
    let out = crate::common::temp_path("cli-bad-prior");
    let (f, o) = (file.to_str().unwrap(), out.to_str().unwrap());
    let base = [
        "report", f, "--column", "x", "--order", "2", "--rate", "100", "--out", o,
    ];
    let weight = ["--prior-a", "1.5,-0.7", "--prior-weight"];
    let cases: [(&[&str], &str); 7] = [
        (
            &["--prior-a", "1.5"],
            "--prior-a has 1 coefficients; --order 2 needs 2",
        ),
        (
            &["--prior-a", "1.5,-0.7,0.1"],
            "--prior-a has 3 coefficients; --order 2 needs 2",
        ),
        (
            &["--prior-a", "1.5,NaN"],
            "--prior-a NaN: coefficients must be finite",
        ),
        (
            &["--prior-a", "inf,-0.7"],
            "--prior-a inf: coefficients must be finite",
        ),
        (
            &["--prior-weight", "300"],
            "the following required arguments were not provided: --prior-a",
        ),
        (
            &[&weight[..], &["300", "--delta", "1"]].concat(),
            "'--prior-weight <PRIOR_WEIGHT>' cannot be used with '--delta <DELTA>'",
        ),
        (&[&weight[..], &["0"]].concat(), "--prior-weight 0:"),
    ];
    for (extra, expected) in cases {
        misused(&[&base[..], extra].concat(), expected);
    }
    assert!(!out.exists(), "{o} was created");
    std::fs::remove_file(file).unwrap();
}
