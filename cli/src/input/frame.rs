//! placeholder
/// x
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// x
    pub stamp_ns: i64,
    /// x
    pub axes: [f64; 6],
}
/// x
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Skipped {
    /// x
    pub undecodable: u64,
    /// x
    pub non_finite: u64,
}
