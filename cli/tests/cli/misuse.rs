//! Every bad input to the `imu-ar` tool: status 2, nothing on stdout, and one line on stderr
//! naming the file, line and problem.

use std::path::PathBuf;

use crate::common;

use common::{column_file, imu_ar, misused, simulated, temp_file};

/// Six input files for a misuse case, named after it: good, text cell, NaN cell, empty,
/// header only, constant. Removed when dropped.
struct Inputs([PathBuf; 6]);

impl Inputs {
    fn new(case: &str) -> Self {
        let contents = [
            "# a comment\nt_s,x\n0,1\n0.01,2\n0.02,1.5\n0.03,0.5\n".to_string(),
            "t_s,x\n0,1\n0.01,abc\n".to_string(),
            "t_s,x\n0,1\n0.01,2\n0.02,NaN\n".to_string(),
            String::new(),
            "t_s,x\n".to_string(),
            format!("x\n{}", "3\n".repeat(50)),
        ];
        let names = ["good", "text", "nan", "empty", "header", "constant"];
        Self(core::array::from_fn(|i| {
            temp_file(&format!("{case}-{}.csv", names[i]), &contents[i])
        }))
    }

    fn paths(&self) -> [&str; 6] {
        core::array::from_fn(|i| self.0[i].to_str().unwrap())
    }
}

impl Drop for Inputs {
    fn drop(&mut self) {
        for f in &self.0 {
            let _ = std::fs::remove_file(f);
        }
    }
}

/// One test per misuse: `name: |[good, text, nan, empty, header, constant]| (args, expected)`.
macro_rules! misuse {
    ($($name:ident: $case:expr;)*) => {
        $(
            #[test]
            fn $name() {
                let inputs = Inputs::new(stringify!($name));
                #[allow(unused_variables)]
                let case: fn([&str; 6]) -> (Vec<&str>, String) = $case;
                let (args, expected) = case(inputs.paths());
                misused(&args, &expected);
            }
        )*
    };
}

misuse! {
    missing_file: |[g, t, n, e, h, c]| (
        vec!["fit", "/nonexistent/log.csv", "--column", "x", "--method", "ls", "--order", "1"],
        "/nonexistent/log.csv: cannot open".into(),
    );
    missing_column: |[g, t, n, e, h, c]| (
        vec!["fit", g, "--column", "gq", "--method", "ls", "--order", "1"],
        format!("{g}: no column 'gq' (columns: t_s, x)"),
    );
    non_numeric_cell: |[g, t, n, e, h, c]| (
        vec!["fit", t, "--column", "x", "--method", "ls", "--order", "1"],
        format!("{t}:3: column 'x': 'abc' is not a number"),
    );
    nan_cell: |[g, t, n, e, h, c]| (
        vec!["fit", n, "--column", "x", "--method", "ls", "--order", "1"],
        format!("{n}:4: column 'x': 'NaN' is not a finite number"),
    );
    empty_file: |[g, t, n, e, h, c]| (
        vec!["adev", e, "--column", "x", "--rate", "100"],
        format!("{e}: empty file"),
    );
    header_only: |[g, t, n, e, h, c]| (
        vec!["adev", h, "--column", "x", "--rate", "100"],
        format!("{h}: no data rows"),
    );
    too_few_samples_for_the_order: |[g, t, n, e, h, c]| (
        vec!["fit", g, "--column", "x", "--method", "ls", "--order", "3"],
        format!("{g}: 4 samples given, at least 8 needed"),
    );
    order_above_32: |[g, t, n, e, h, c]| (
        vec!["fit", g, "--column", "x", "--method", "ls", "--order", "33"],
        "--order 33: the order must be 1 to 32".into(),
    );
    order_zero: |[g, t, n, e, h, c]| (
        vec!["fit", g, "--column", "x", "--method", "ls", "--order", "0"],
        "--order 0: the order must be 1 to 32".into(),
    );
    max_order_above_32: |[g, t, n, e, h, c]| (
        vec!["order", g, "--column", "x", "--method", "ls", "--max-order", "40"],
        "--max-order 40: the order must be 1 to 32".into(),
    );
    constant_data: |[g, t, n, e, h, c]| (
        vec!["fit", c, "--column", "x", "--method", "burg", "--order", "1"],
        format!("{c}: data have zero variance"),
    );
    constant_allan_deviation: |[g, t, n, e, h, c]| (
        vec!["adev", c, "--column", "x", "--rate", "100"],
        format!("{c}: the record is constant (a stuck sensor?): every Allan variance is zero"),
    );
    negative_rate: |[g, t, n, e, h, c]| (
        vec!["adev", g, "--column", "x", "--rate", "-5"],
        "--rate -5: must be a positive number".into(),
    );
    zero_rate: |[g, t, n, e, h, c]| (
        vec!["fit", g, "--column", "x", "--method", "ls", "--order", "1", "--rate", "0"],
        "--rate 0: must be a positive number".into(),
    );
    unknown_method: |[g, t, n, e, h, c]| (
        vec!["fit", g, "--column", "x", "--method", "kalman", "--order", "1"],
        "invalid value 'kalman' for '--method".into(),
    );
    order_not_a_number: |[g, t, n, e, h, c]| (
        vec!["fit", g, "--column", "x", "--method", "ls", "--order", "two"],
        "invalid value 'two' for '--order".into(),
    );
    non_stationary_simulation: |[g, t, n, e, h, c]| (
        vec!["simulate", "--a", "1.0", "--sigma", "1", "--n", "10", "--seed", "1"],
        "the model is not stationary".into(),
    );
    nan_sigma: |[g, t, n, e, h, c]| (
        vec!["simulate", "--a", "0.5", "--sigma", "nan", "--n", "10", "--seed", "1"],
        "--sigma NaN: must be finite".into(),
    );
    missing_argument: |[g, t, n, e, h, c]| (
        vec!["adev", g, "--rate", "100"],
        "the following required arguments were not provided".into(),
    );
}

/// Issue 23 item 5: an error names the record's own line, with CRLF line ends and after
/// blank lines and comments.
#[test]
fn csv_errors_name_the_records_own_line() {
    let cases = [
        ("crlf", "x\r\nabc\r\n2\r\n", 2),
        ("blank", "x\n1\n\n\nabc\n", 5),
        ("crlf-blank", "x\r\n1\r\n\r\n2\r\nabc\r\n", 5),
        ("comment", "# c\nx\n1\n# note\n\n2\nabc\n", 7),
    ];
    for (name, contents, line) in cases {
        let file = temp_file(&format!("line-{name}.csv"), contents);
        let f = file.to_str().unwrap();
        misused(
            &["fit", f, "--column", "x", "--method", "ls", "--order", "1"],
            &format!("{f}:{line}: column 'x': 'abc' is not a number"),
        );
        std::fs::remove_file(file).unwrap();
    }
}

/// Issue 23 item 6: a fit with zero residual degrees of freedom is refused.
#[test]
fn fits_without_residual_degrees_of_freedom_are_refused() {
    let two = temp_file("dof-two.csv", "x\n1\n2\n");
    let t = two.to_str().unwrap();
    for (method, needed) in [("ls", 4), ("burg", 3), ("yule-walker", 3)] {
        misused(
            &[
                "fit", t, "--column", "x", "--method", method, "--order", "1",
            ],
            &format!("{t}: 2 samples given, at least {needed} needed"),
        );
    }
    let file = simulated("dof-500.csv", "0.5", "500", "1");
    let f = file.to_str().unwrap();
    misused(
        &[
            "fit",
            f,
            "--column",
            "x",
            "--method",
            "ls",
            "--order",
            "1",
            "--decimate",
            "250",
        ],
        &format!("{f}: 2 samples given, at least 4 needed"),
    );
    std::fs::remove_file(two).unwrap();
    std::fs::remove_file(file).unwrap();
}

/// Issue 23 item 10: huge values are called an overflow, not zero variance, a singular
/// system or a bad `--delta` that was never given.
#[test]
fn huge_values_are_reported_as_an_overflow() {
    let file = column_file("huge.csv", (0..500).map(|i| format!("{}e160", 1 + i % 7)));
    let f = file.to_str().unwrap();
    for method in ["ls", "burg", "yule-walker", "rls", "lattice"] {
        misused(
            &[
                "fit", f, "--column", "x", "--method", method, "--order", "2",
            ],
            "overflows f64",
        );
    }
    misused(
        &["compare", f, "--column", "x", "--order", "2"],
        "overflows f64",
    );
    std::fs::remove_file(file).unwrap();
}

/// Samples whose differences underflow f64: every Allan variance zero (fourteen zeros, exit
/// 0, from `adev` before), refused as `noise` refuses them.
#[test]
fn an_allan_variance_that_underflows_is_refused() {
    let file = column_file("tiny.csv", (0..500).map(|i| format!("{}e-300", 1 + i % 7)));
    misused(
        &[
            "adev",
            file.to_str().unwrap(),
            "--column",
            "x",
            "--rate",
            "100",
        ],
        "the Allan variance underflows f64",
    );
    std::fs::remove_file(file).unwrap();
}

/// Issue 23 item 10: `compare` names the training part when it is too short.
#[test]
fn compare_names_the_training_part_when_too_short() {
    let file = simulated("compare-64.csv", "0.5", "64", "2");
    let f = file.to_str().unwrap();
    misused(
        &["compare", f, "--column", "x", "--order", "32"],
        "the training part (--train 0.5 of 64 samples) has 32 samples, at least 66 needed",
    );
    std::fs::remove_file(file).unwrap();
}

/// Issue 23 item 10: `order` on too few samples is an error, not "selected 0" over a table
/// of nulls.
#[test]
fn order_on_three_samples_is_refused() {
    let file = temp_file("order-3.csv", "x\n1\n2\n3\n");
    let f = file.to_str().unwrap();
    misused(
        &[
            "order",
            f,
            "--column",
            "x",
            "--method",
            "ls",
            "--max-order",
            "1",
        ],
        &format!("{f}: 3 samples given, at least 4 needed"),
    );
    std::fs::remove_file(file).unwrap();
}

/// Issue 23 item 12: an error shows a long cell cut short.
#[test]
fn an_error_shortens_a_long_cell() {
    let cell = "1".repeat(100_000);
    let file = column_file("long-cell.csv", [cell]);
    let f = file.to_str().unwrap();
    let args = ["fit", f, "--column", "x", "--method", "ls", "--order", "1"];
    misused(
        &args,
        &format!(
            "{f}:2: column 'x': '{}... (100000 bytes)' is not a finite number",
            "1".repeat(40)
        ),
    );
    assert!(imu_ar(&args).stderr.len() < 200 + f.len());
    std::fs::remove_file(file).unwrap();
}

/// Issue 23 item 12: a column named twice in the header is an error.
#[test]
fn a_duplicate_column_name_is_an_error() {
    let file = temp_file("dup.csv", "x,y,x\n1,2,3\n2,3,4\n1,5,2\n4,4,4\n");
    let f = file.to_str().unwrap();
    misused(
        &["fit", f, "--column", "x", "--method", "ls", "--order", "1"],
        &format!("{f}: the header names column 'x' 2 times"),
    );
    std::fs::remove_file(file).unwrap();
}

/// The fixed-point lattice's range of `lambda` is `[0.9, 1]`: below it, the error names
/// `--lambda`, not the scale.
#[test]
fn fixed_fit_refuses_a_lambda_below_its_range() {
    let file = simulated("fixed-lambda.csv", "0.7,-0.2", "2000", "5");
    let f = file.to_str().unwrap();
    misused(
        &[
            "fit", f, "--column", "x", "--method", "lattice", "--scalar", "fixed", "--order", "2",
            "--lambda", "0.5",
        ],
        "--lambda 0.5: the fixed-point lattice needs lambda in [0.9, 1]",
    );
}
