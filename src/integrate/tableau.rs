//! Butcher tableaux of the explicit Runge–Kutta methods.
//!
//! ## DOPRI5(4): Dormand–Prince 5(4), seven stages, FSAL
//!
//! J. R. Dormand, P. J. Prince, *A family of embedded Runge–Kutta formulae*, J. Comput.
//! Appl. Math. 6(1), 19–26 (1980); [HNW, II.5, Table 5.2]. The 5th-order solution `b`
//! propagates (local extrapolation); the 4th-order `b̂` only estimates the error. The
//! last row of `A` equals `b` and `c₇ = 1`, so the 7th stage is `f(t + h, y₁)`: it is the
//! first stage of the next step (First Same As Last) and costs nothing there.
//!
//! ```text
//!   0    |
//!   1/5  | 1/5
//!   3/10 | 3/40        9/40
//!   4/5  | 44/45      −56/15       32/9
//!   8/9  | 19372/6561 −25360/2187  64448/6561  −212/729
//!   1    | 9017/3168  −355/33      46732/5247   49/176   −5103/18656
//!   1    | 35/384      0           500/1113     125/192  −2187/6784    11/84
//!  ------+------------------------------------------------------------------------
//!   b    | 35/384      0           500/1113     125/192  −2187/6784    11/84     0
//!   b̂    | 5179/57600  0           7571/16695   393/640  −92097/339200 187/2100  1/40
//!   e=b−b̂| 71/57600    0          −71/16695     71/1920  −17253/339200 22/525   −1/40
//! ```
//!
//! The continuous extension of order 4 is Shampine's [L. F. Shampine, *Some practical
//! Runge–Kutta formulas*, Math. Comp. 46(173), 135–150 (1986)] in the form of
//! [HNW, II.6, Eq. (6.12)] and Hairer's code `DOPRI5` (`CONTD5`): with `θ = (t − t₀)/h`,
//!
//! ```text
//!   u(θ) = r₁ + θ (r₂ + (1−θ) (r₃ + θ (r₄ + (1−θ) r₅)))
//!   r₁ = y₀,  r₂ = y₁ − y₀,  r₃ = h k₁ − r₂,  r₄ = r₂ − h k₇ − r₃,
//!   r₅ = h (d₁ k₁ + d₃ k₃ + d₄ k₄ + d₅ k₅ + d₆ k₆ + d₇ k₇)
//!   d  = (−12715105075/11282082432, 0, 87487479700/32700410799,
//!         −10690763975/1880347072, 701980252875/199316789632,
//!         −1453857185/822651844, 69997945/29380423)
//! ```
//!
//! `u` interpolates `y₀, y₁` and the slopes `k₁ = f(t₀, y₀)`, `k₇ = f(t₁, y₁)` at the ends
//! (with `r₅ = 0` it is the cubic Hermite interpolant, which RK4 uses).
//!
//! ## RK4: the classical Runge–Kutta method [HNW, II.1, Table 1.2, left]
//!
//! ```text
//!   0   |
//!   1/2 | 1/2
//!   1/2 | 0    1/2
//!   1   | 0    0    1
//!  -----+--------------------
//!   b   | 1/6  1/3  1/3  1/6
//! ```

//!
//! ## DOP853: Dormand–Prince 8(5,3), twelve stages, FSAL, dense output of order 7
//!
//! E. Hairer, S. P. Nørsett, G. Wanner, *Solving Ordinary Differential Equations I*, 2nd
//! ed., Springer 1993 [HNW, II.10, the code `DOP853`]; the coefficients are those of
//! Hairer's `dop853.f` (as in SciPy's `_ivp/dop853_coefficients.py`), written to ~30
//! digits and rounded once to doubles by the compiler. The 8th-order solution `b`
//! propagates; the step is controlled by the error estimate of Hairer's code, which
//! combines a 5th-order `ê₅ = b − b̂₅` and a 3rd-order `ê₃ = b − b̂₃` [HNW, II.10,
//! Eq. (10.10)]:
//!
//! ```text
//!   e5ᵢ = Σⱼ ê₅ⱼ kⱼᵢ,  e3ᵢ = Σⱼ ê₃ⱼ kⱼᵢ,  skᵢ = atol + rtol · max(|y₀ᵢ|, |y₁ᵢ|)
//!   E5 = Σᵢ (e5ᵢ/skᵢ)²,  E3 = Σᵢ (e3ᵢ/skᵢ)²
//!   err = |h| · E5 / √(n (E5 + 0.01 E3))
//! ```
//!
//! The continuous extension of order 7 needs three more stages `k₁₄, k₁₅, k₁₆` (rows 14–16
//! of the extended table, over `k₁ … k₁₃`, `k₁₃ = f(t₁, y₁)`), then
//!
//! ```text
//!   u(θ) = y₀ + θ (r₂ + (1−θ) (r₃ + θ (r₄ + (1−θ) (r₅ + θ (r₆ + (1−θ) (r₇ + θ r₈))))))
//!   r₂, r₃, r₄ as for DOPRI5;   r₅₊ₘ = h Σⱼ D_{m,j} kⱼ,  m = 0 … 3
//! ```
//!
//! All three methods are values of [`Tableau`]: [`DOPRI5`], [`RK4`], [`DOP853`]; one
//! stepper (`RungeKutta`) runs each from its tableau.

// DOP853's published digits (~30) are kept as published.
#![allow(clippy::excessive_precision)]

use crate::math::Real;

/// How a method estimates its local error (an adaptive method has one).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ErrorEstimate {
    /// None: the method takes a fixed step (RK4).
    None,
    /// `err = h Σⱼ eⱼ kⱼ` over the stages and `k_{s+1} = f(t₁, y₁)`, in the weighted RMS
    /// norm of [HNW, II.4, Eq. (4.11)] (DOPRI5).
    Embedded {
        /// `e = b − b̂`, over `k₁ … k_{s+1}`.
        e: &'static [Real],
    },
    /// DOP853's pair of estimates of orders 5 and 3 (see the module's doc).
    Dop853 {
        /// `ê₅`, over `k₁ … k_s`.
        e5: &'static [Real],
        /// `ê₃`, over `k₁ … k_s`.
        e3: &'static [Real],
    },
}

/// The continuous extension (dense output) of a method.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DenseOutput {
    /// The cubic Hermite interpolant of `(y₀, f₀, y₁, f₁)`, order 3 (RK4).
    Hermite,
    /// Shampine's quartic term `r₅ = h Σ dⱼ kⱼ` over `k₁ … k_{s+1}`, order 4 (DOPRI5).
    Shampine {
        /// `d`.
        d: &'static [Real],
    },
    /// Three more stages and four more terms, order 7 (DOP853).
    Extended {
        /// Nodes of the extra stages.
        c: &'static [Real],
        /// Their rows of `A`, over every stage before each (`k₁ … k_{s+1}`, then the extra
        /// ones).
        a: &'static [&'static [Real]],
        /// The weights of `r₅ …` over all the stages.
        d: &'static [[Real; 16]],
    },
}

/// An explicit Runge–Kutta method as data: its Butcher tableau, its error estimate and
/// its continuous extension.
///
/// Stage 1 is `k₁ = f(t₀, y₀)`, the derivative at the end of the previous step (every
/// method here evaluates `k_{s+1} = f(t₁, y₁)` after the step, for the dense output and
/// the next step: First Same As Last). For `i = 2 … s`:
///
/// ```text
///   kᵢ = f(t₀ + cᵢ h, y₀ + h Σⱼ<ᵢ aᵢⱼ kⱼ),   y₁ = y₀ + (h / b_den) Σⱼ bⱼ kⱼ
/// ```
///
/// Zero coefficients are skipped; a row with one nonzero coefficient is applied as
/// `y₀ + (h aᵢⱼ) kⱼ`, and a node `cᵢ = 1` is the step's end `t₁` itself — the forms of
/// the codes these methods reproduce bit for bit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tableau {
    /// The method's name.
    pub name: &'static str,
    /// The order of `y₁`.
    pub order: u32,
    /// The nodes `c₁ … c_s` (`c₁ = 0`).
    pub c: &'static [Real],
    /// Rows 2 … s of `A`: `a[i − 2]` holds `a_{i,1} … a_{i,i−1}`.
    pub a: &'static [&'static [Real]],
    /// The weights `b₁ … b_s` times `b_den`.
    pub b: &'static [Real],
    /// The common denominator of `b` (1 but for RK4's `(1, 2, 2, 1)/6`).
    pub b_den: Real,
    /// The error estimate.
    pub error: ErrorEstimate,
    /// The step-size controller's exponents `(κ₀, κ₁)`: `err^(κ₀ − κ₁ β)` (Hairer's
    /// `EXPO1`: `(1/5, 0.75)` for DOPRI5, `(1/8, 0.2)` for DOP853).
    pub controller: (Real, Real),
    /// The continuous extension.
    pub dense: DenseOutput,
}

impl Tableau {
    /// The number of stages `s` of a step (without `f(t₁, y₁)` nor the extra stages of
    /// the dense output).
    pub fn stages(&self) -> usize {
        self.c.len()
    }

    /// Evaluations of `f` per step: the stages 2 … s, `f(t₁, y₁)` and the extra stages of
    /// the dense output (which `RungeKutta` evaluates only when the step's dense output
    /// is completed: `Stepper::complete_dense`).
    pub fn evaluations_per_step(&self) -> u64 {
        let extra = match self.dense {
            DenseOutput::Extended { c, .. } => c.len(),
            _ => 0,
        };
        (self.stages() + extra) as u64
    }
}

/// Dormand–Prince 5(4) with Shampine's dense output of order 4.
pub const DOPRI5: Tableau = Tableau {
    name: "dopri5",
    order: 5,
    c: &[0.0, C2, C3, C4, C5, 1.0],
    a: &[
        &[A21],
        &[A31, A32],
        &[A41, A42, A43],
        &[A51, A52, A53, A54],
        &[A61, A62, A63, A64, A65],
    ],
    b: &[A71, 0.0, A73, A74, A75, A76],
    b_den: 1.0,
    error: ErrorEstimate::Embedded {
        e: &[E1, 0.0, E3, E4, E5, E6, E7],
    },
    controller: (0.2, 0.75),
    dense: DenseOutput::Shampine {
        d: &[D1, 0.0, D3, D4, D5, D6, D7],
    },
};

/// The classical Runge–Kutta method of order 4 with the cubic Hermite dense output.
pub const RK4: Tableau = Tableau {
    name: "rk4",
    order: 4,
    c: &[0.0, 0.5, 0.5, 1.0],
    a: &[&[0.5], &[0.0, 0.5], &[0.0, 0.0, 1.0]],
    b: &[1.0, 2.0, 2.0, 1.0],
    b_den: 6.0,
    error: ErrorEstimate::None,
    controller: (0.0, 0.0),
    dense: DenseOutput::Hermite,
};

/// Dormand–Prince 8(5,3) with its dense output of order 7.
pub const DOP853: Tableau = Tableau {
    name: "dop853",
    order: 8,
    c: &DOP853_C,
    a: &DOP853_A,
    b: &DOP853_B,
    b_den: 1.0,
    error: ErrorEstimate::Dop853 {
        e5: &DOP853_E5,
        e3: &DOP853_E3,
    },
    controller: (0.125, 0.2),
    dense: DenseOutput::Extended {
        c: &DOP853_C_EXTRA,
        a: &DOP853_A_EXTRA,
        d: &DOP853_D,
    },
};

// The published digits of DOP853 (Hairer's dop853.f), rounded once to doubles.
/// DOP853 nodes `c₁ … c₁₂` (`c₁ = 0`, `c₁₂ = 1`).
const DOP853_C: [Real; 12] = [
    0.0,
    0.526001519587677318785587544488e-01,
    0.789002279381515978178381316732e-01,
    0.118350341907227396726757197510,
    0.281649658092772603273242802490,
    0.333333333333333333333333333333,
    0.25,
    0.307692307692307692307692307692,
    0.651282051282051282051282051282,
    0.6,
    0.857142857142857142857142857142,
    1.0,
];

/// DOP853 coupling coefficients, rows 2–12 (row `i` holds `a_i1 … a_i,i−1`).
const DOP853_A: [&[Real]; 11] = [
    &[5.26001519587677318785587544488e-2],
    &[
        1.97250569845378994544595329183e-2,
        5.91751709536136983633785987549e-2,
    ],
    &[
        2.95875854768068491816892993775e-2,
        0.0,
        8.87627564304205475450678981324e-2,
    ],
    &[
        2.41365134159266685502369798665e-1,
        0.0,
        -8.84549479328286085344864962717e-1,
        9.24834003261792003115737966543e-1,
    ],
    &[
        3.7037037037037037037037037037e-2,
        0.0,
        0.0,
        1.70828608729473871279604482173e-1,
        1.25467687566822425016691814123e-1,
    ],
    &[
        3.7109375e-2,
        0.0,
        0.0,
        1.70252211019544039314978060272e-1,
        6.02165389804559606850219397283e-2,
        -1.7578125e-2,
    ],
    &[
        3.70920001185047927108779319836e-2,
        0.0,
        0.0,
        1.70383925712239993810214054705e-1,
        1.07262030446373284651809199168e-1,
        -1.53194377486244017527936158236e-2,
        8.27378916381402288758473766002e-3,
    ],
    &[
        6.24110958716075717114429577812e-1,
        0.0,
        0.0,
        -3.36089262944694129406857109825,
        -8.68219346841726006818189891453e-1,
        2.75920996994467083049415600797e1,
        2.01540675504778934086186788979e1,
        -4.34898841810699588477366255144e1,
    ],
    &[
        4.77662536438264365890433908527e-1,
        0.0,
        0.0,
        -2.48811461997166764192642586468,
        -5.90290826836842996371446475743e-1,
        2.12300514481811942347288949897e1,
        1.52792336328824235832596922938e1,
        -3.32882109689848629194453265587e1,
        -2.03312017085086261358222928593e-2,
    ],
    &[
        -9.3714243008598732571704021658e-1,
        0.0,
        0.0,
        5.18637242884406370830023853209,
        1.09143734899672957818500254654,
        -8.14978701074692612513997267357,
        -1.85200656599969598641566180701e1,
        2.27394870993505042818970056734e1,
        2.49360555267965238987089396762,
        -3.0467644718982195003823669022,
    ],
    &[
        2.27331014751653820792359768449,
        0.0,
        0.0,
        -1.05344954667372501984066689879e1,
        -2.00087205822486249909675718444,
        -1.79589318631187989172765950534e1,
        2.79488845294199600508499808837e1,
        -2.85899827713502369474065508674,
        -8.87285693353062954433549289258,
        1.23605671757943030647266201528e1,
        6.43392746015763530355970484046e-1,
    ],
];

/// DOP853 8th-order weights `b` (row 13 of the extended table; `b₂ … b₅ = 0`).
const DOP853_B: [Real; 12] = [
    5.42937341165687622380535766363e-2,
    0.0,
    0.0,
    0.0,
    0.0,
    4.45031289275240888144113950566,
    1.89151789931450038304281599044,
    -5.8012039600105847814672114227,
    3.1116436695781989440891606237e-1,
    -1.52160949662516078556178806805e-1,
    2.01365400804030348374776537501e-1,
    4.47106157277725905176885569043e-2,
];

/// DOP853 `ê₅ = b − b̂₅`, the 5th-order error weights (`ER` in Hairer's code).
const DOP853_E5: [Real; 12] = [
    0.1312004499419488073250102996e-1,
    0.0,
    0.0,
    0.0,
    0.0,
    -0.1225156446376204440720569753e1,
    -0.4957589496572501915214079952,
    0.1664377182454986536961530415e1,
    -0.3503288487499736816886487290,
    0.3341791187130174790297318841,
    0.8192320648511571246570742613e-1,
    -0.2235530786388629525884427845e-1,
];

/// The weights of the 3rd-order `b̂₃` where it differs from `b` (`BHH1, BHH2, BHH3`, on `k₁, k₉, k₁₂`).
const DOP853_BHH: [Real; 3] = [
    0.244094488188976377952755905512,
    0.733846688281611857341361741547,
    0.220588235294117647058823529412e-1,
];

/// DOP853 `ê₃ = b − b̂₃`.
const DOP853_E3: [Real; 12] = [
    DOP853_B[0] - DOP853_BHH[0],
    DOP853_B[1],
    DOP853_B[2],
    DOP853_B[3],
    DOP853_B[4],
    DOP853_B[5],
    DOP853_B[6],
    DOP853_B[7],
    DOP853_B[8] - DOP853_BHH[1],
    DOP853_B[9],
    DOP853_B[10],
    DOP853_B[11] - DOP853_BHH[2],
];

/// Nodes of DOP853's three extra stages of the dense output, `c₁₄, c₁₅, c₁₆`.
const DOP853_C_EXTRA: [Real; 3] = [0.1, 0.2, 0.777777777777777777777777777778];

/// Rows 14–16 of DOP853's extended table, over `k₁ … k₁₅` (`k₁₃ = f(t₁, y₁)`).
const DOP853_A_EXTRA: [&[Real]; 3] = [
    &[
        5.61675022830479523392909219681e-2,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        2.53500210216624811088794765333e-1,
        -2.46239037470802489917441475441e-1,
        -1.24191423263816360469010140626e-1,
        1.5329179827876569731206322685e-1,
        8.20105229563468988491666602057e-3,
        7.56789766054569976138603589584e-3,
        -8.298e-3,
    ],
    &[
        3.18346481635021405060768473261e-2,
        0.0,
        0.0,
        0.0,
        0.0,
        2.83009096723667755288322961402e-2,
        5.35419883074385676223797384372e-2,
        -5.49237485713909884646569340306e-2,
        0.0,
        0.0,
        -1.08347328697249322858509316994e-4,
        3.82571090835658412954920192323e-4,
        -3.40465008687404560802977114492e-4,
        1.41312443674632500278074618366e-1,
    ],
    &[
        -4.28896301583791923408573538692e-1,
        0.0,
        0.0,
        0.0,
        0.0,
        -4.69762141536116384314449447206,
        7.68342119606259904184240953878,
        4.06898981839711007970213554331,
        3.56727187455281109270669543021e-1,
        0.0,
        0.0,
        0.0,
        -1.39902416515901462129418009734e-3,
        2.9475147891527723389556272149,
        -9.15095847217987001081870187138,
    ],
];

/// DOP853 dense-output weights of `r₅ … r₈` over `k₁ … k₁₆` (`D4 … D7` in Hairer's code).
const DOP853_D: [[Real; 16]; 4] = [
    [
        -0.84289382761090128651353491142e1,
        0.0,
        0.0,
        0.0,
        0.0,
        0.56671495351937776962531783590,
        -0.30689499459498916912797304727e1,
        0.23846676565120698287728149680e1,
        0.21170345824450282767155149946e1,
        -0.87139158377797299206789907490,
        0.22404374302607882758541771650e1,
        0.63157877876946881815570249290,
        -0.88990336451333310820698117400e-1,
        0.18148505520854727256656404962e2,
        -0.91946323924783554000451984436e1,
        -0.44360363875948939664310572000e1,
    ],
    [
        0.10427508642579134603413151009e2,
        0.0,
        0.0,
        0.0,
        0.0,
        0.24228349177525818288430175319e3,
        0.16520045171727028198505394887e3,
        -0.37454675472269020279518312152e3,
        -0.22113666853125306036270938578e2,
        0.77334326684722638389603898808e1,
        -0.30674084731089398182061213626e2,
        -0.93321305264302278729567221706e1,
        0.15697238121770843886131091075e2,
        -0.31139403219565177677282850411e2,
        -0.93529243588444783865713862664e1,
        0.35816841486394083752465898540e2,
    ],
    [
        0.19985053242002433820987653617e2,
        0.0,
        0.0,
        0.0,
        0.0,
        -0.38703730874935176555105901742e3,
        -0.18917813819516756882830838328e3,
        0.52780815920542364900561016686e3,
        -0.11573902539959630126141871134e2,
        0.68812326946963000169666922661e1,
        -0.10006050966910838403183860980e1,
        0.77771377980534432092869265740,
        -0.27782057523535084065932004339e1,
        -0.60196695231264120758267380846e2,
        0.84320405506677161018159903784e2,
        0.11992291136182789328035130030e2,
    ],
    [
        -0.25693933462703749003312586129e2,
        0.0,
        0.0,
        0.0,
        0.0,
        -0.15418974869023643374053993627e3,
        -0.23152937917604549567536039109e3,
        0.35763911791061412378285349910e3,
        0.93405324183624310003907691704e2,
        -0.37458323136451633156875139351e2,
        0.10409964950896230045147246184e3,
        0.29840293426660503123344363579e2,
        -0.43533456590011143754432175058e2,
        0.96324553959188282948394950600e2,
        -0.39177261675615439165231486172e2,
        -0.14972683625798562581422125276e3,
    ],
];

/// DOPRI5 nodes `c₂ … c₆` (`c₁ = 0`, `c₇ = 1`).
pub(crate) const C2: Real = 1.0 / 5.0;
pub(crate) const C3: Real = 3.0 / 10.0;
pub(crate) const C4: Real = 4.0 / 5.0;
pub(crate) const C5: Real = 8.0 / 9.0;

/// DOPRI5 coupling coefficients `a_ij`, row by row.
pub(crate) const A21: Real = 1.0 / 5.0;

pub(crate) const A31: Real = 3.0 / 40.0;
pub(crate) const A32: Real = 9.0 / 40.0;

pub(crate) const A41: Real = 44.0 / 45.0;
pub(crate) const A42: Real = -56.0 / 15.0;
pub(crate) const A43: Real = 32.0 / 9.0;

pub(crate) const A51: Real = 19372.0 / 6561.0;
pub(crate) const A52: Real = -25360.0 / 2187.0;
pub(crate) const A53: Real = 64448.0 / 6561.0;
pub(crate) const A54: Real = -212.0 / 729.0;

pub(crate) const A61: Real = 9017.0 / 3168.0;
pub(crate) const A62: Real = -355.0 / 33.0;
pub(crate) const A63: Real = 46732.0 / 5247.0;
pub(crate) const A64: Real = 49.0 / 176.0;
pub(crate) const A65: Real = -5103.0 / 18656.0;

/// Last row = 5th-order weights `b` (`b₂ = b₇ = 0`).
pub(crate) const A71: Real = 35.0 / 384.0;
pub(crate) const A73: Real = 500.0 / 1113.0;
pub(crate) const A74: Real = 125.0 / 192.0;
pub(crate) const A75: Real = -2187.0 / 6784.0;
pub(crate) const A76: Real = 11.0 / 84.0;

/// Error weights `e = b − b̂` (`e₂ = 0`).
pub(crate) const E1: Real = 71.0 / 57600.0;
pub(crate) const E3: Real = -71.0 / 16695.0;
pub(crate) const E4: Real = 71.0 / 1920.0;
pub(crate) const E5: Real = -17253.0 / 339200.0;
pub(crate) const E6: Real = 22.0 / 525.0;
pub(crate) const E7: Real = -1.0 / 40.0;

/// Dense-output weights `d` of `r₅` (`d₂ = 0`).
pub(crate) const D1: Real = -12715105075.0 / 11282082432.0;
pub(crate) const D3: Real = 87487479700.0 / 32700410799.0;
pub(crate) const D4: Real = -10690763975.0 / 1880347072.0;
pub(crate) const D5: Real = 701980252875.0 / 199316789632.0;
pub(crate) const D6: Real = -1453857185.0 / 822651844.0;
pub(crate) const D7: Real = 69997945.0 / 29380423.0;
