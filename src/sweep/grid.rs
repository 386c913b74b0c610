//! The grid of a sweep (the Cartesian product of its parameters, with a run index) and
//! the share of it that one shard runs.

use std::fmt;
use std::str::FromStr;

use super::spec::{MAX_RUNS, ParamSpec, Value};
use super::{ShardError, SpecError};

/// The Cartesian product of the swept parameters, in a fixed order: the first parameter
/// varies slowest and the last fastest, as nested loops written in the order the
/// parameters are given. The run index is the mixed-radix number of the value indices:
/// `index = Σ_j k_j · stride_j`, `stride_j = Π_{i>j} len_i`. No parameter: one run, the
/// scene as it is.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    params: Vec<ParamSpec>,
    /// `stride_j` of each parameter.
    strides: Vec<usize>,
    /// The number of runs.
    len: usize,
}

impl Grid {
    /// The grid of `params`. Errors: a parameter given twice, more than [`MAX_RUNS`] runs.
    pub fn new(params: Vec<ParamSpec>) -> Result<Grid, SpecError> {
        for (j, p) in params.iter().enumerate() {
            if params[..j].iter().any(|o| o.param == p.param) {
                return Err(SpecError::Duplicate {
                    name: p.param.to_string(),
                });
            }
        }
        let mut strides = vec![0; params.len()];
        let mut len = 1usize;
        for (j, p) in params.iter().enumerate().rev() {
            strides[j] = len;
            len = len
                .checked_mul(p.len())
                .filter(|&n| n <= MAX_RUNS)
                .ok_or(SpecError::TooLarge { max: MAX_RUNS })?;
        }
        Ok(Grid {
            params,
            strides,
            len,
        })
    }

    /// The parameters, in the order given.
    pub fn params(&self) -> &[ParamSpec] {
        &self.params
    }

    /// The number of runs.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the grid has no run (a parameter with no value; never for parsed specs).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The value of parameter `j` at run `index` (`index < len()`): its value
    /// `k_j = ⌊index / stride_j⌋ mod len_j`.
    pub fn value(&self, index: usize, j: usize) -> Value {
        let p = &self.params[j];
        p.value((index / self.strides[j]) % p.len())
    }
}

/// The share of a grid that one process runs, `i/N`: the runs whose index is `i` modulo
/// `N` (`0 ≤ i < N`). Strided rather than contiguous blocks: the cost of a run varies
/// smoothly over the grid (a larger `e` bounces longer, a smaller tolerance takes more
/// steps), so contiguous blocks would give one shard all the slow corner of the grid,
/// while strides spread every region over all shards. `0/1` is the whole grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// `i`, this shard.
    pub index: usize,
    /// `N`, the number of shards.
    pub count: usize,
}

impl Shard {
    /// The whole grid, `0/1`.
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// The shard `index/count`. Errors: `count = 0` or `index ≥ count`.
    pub fn new(index: usize, count: usize) -> Result<Shard, ShardError> {
        if count == 0 || index >= count {
            return Err(ShardError {
                text: format!("{index}/{count}"),
                reason: "expected i/N with 0 ≤ i < N",
            });
        }
        Ok(Shard { index, count })
    }

    /// Whether run `run` is in this shard: `run mod N = i`.
    pub fn contains(&self, run: usize) -> bool {
        run % self.count == self.index
    }

    /// The runs of this shard among `len`, in increasing order.
    pub fn runs(&self, len: usize) -> impl ExactSizeIterator<Item = usize> + use<> {
        (self.index..len).step_by(self.count)
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = ShardError;

    /// `i/N` (as in a Slurm job array: `$SLURM_ARRAY_TASK_ID/16`).
    fn from_str(s: &str) -> Result<Shard, ShardError> {
        let bad = |reason| ShardError {
            text: s.to_owned(),
            reason,
        };
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| bad("expected i/N, e.g. 3/16"))?;
        let i: usize = i
            .trim()
            .parse()
            .map_err(|_| bad("i is not a whole number ≥ 0"))?;
        let n: usize = n
            .trim()
            .parse()
            .map_err(|_| bad("N is not a whole number ≥ 1"))?;
        Shard::new(i, n).map_err(|e| bad(e.reason))
    }
}
