//! The adaptive explicit pairs: the Bogacki–Shampine 3(2) pair (Bogacki and Shampine, 1989)
//! with its cubic Hermite dense output, the Dormand–Prince 5(4) pair with Shampine's dense
//! output, and DOP853 with its error estimators and dense output, as Hairer, Nørsett and Wanner
//! give them;
//! each pair's coefficients and the facts of its step control, as the stepping code reads them.
//! A pair with one error estimate and a polynomial dense output over its stages is added here
//! alone: the stepping code reads it through these functions.

use super::Tableau;

/// An adaptive explicit pair with local extrapolation (the higher order propagates).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Pair {
    Bs3,
    Dopri5,
    Dop853,
}

impl Pair {
    /// The h·|λ| past which [`super::Adaptive::stiff`] counts a step as limited by stability: the
    /// stability boundary on the negative real axis, rounded up a little.
    pub fn stiffness_bound(self) -> f64 {
        match self {
            // Its stage before the end is at t + 3h/4, not at the end's time as the test
            // needs: no step is counted as limited by stability.
            Pair::Bs3 => f64::INFINITY,
            Pair::Dopri5 => 3.25,
            Pair::Dop853 => 6.1,
        }
    }

    /// The level the pair holds its local error estimate to (weighted by atol + rtol·|y|) for
    /// a run's `tolerance`, so that a tolerance means one accuracy whichever method runs (see
    /// docs/simulating.md): dop853's final errors come out near the tolerance as it is, while
    /// dopri5's, whose steps are more numerous and each less accurate than its estimate says,
    /// come out several times above it; a tenth of the tolerance brings them to dop853's
    /// (`lagrange-bench tolerance`). bs3's, of a second-order estimate, come out 17 to 70 times
    /// above dop853's (the oscillator, the simple and the double pendulum at 1e-5 … 1e-9): a
    /// thirtieth brings them within a factor of 3.
    pub fn error_target(self, tolerance: f64) -> f64 {
        match self {
            Pair::Bs3 => tolerance / 30.0,
            Pair::Dopri5 => tolerance / 10.0,
            Pair::Dop853 => tolerance,
        }
    }

    /// The tableau of the pair's propagating (higher-order) method, whose stability region
    /// limits its step.
    pub(crate) fn tableau(self) -> Tableau {
        match self {
            Pair::Bs3 => (&BS3_A, &BS3_B),
            Pair::Dopri5 => (&DP5_A, &DP5_B),
            Pair::Dop853 => (&DOP853_A[..12], DOP853_A[12]),
        }
    }

    /// The order of the error estimate: the step control's exponent is −1/(order + 1).
    pub(crate) fn estimate_order(self) -> f64 {
        match self {
            Pair::Bs3 => 2.0,
            Pair::Dopri5 => 4.0,
            Pair::Dop853 => 7.0,
        }
    }

    /// The stages an [`super::Adaptive`] keeps: those of a step, the derivative at its end,
    /// and those its dense output evaluates.
    pub(crate) fn kept_stages(self) -> usize {
        match self {
            Pair::Bs3 => 4,
            Pair::Dopri5 => 7,
            Pair::Dop853 => 16,
        }
    }

    /// The weights of a pair's one error estimate, h·Σⱼ eⱼ·kⱼ over its stages and the
    /// derivative at the end of the step; `None` for DOP853, which weighs two estimates.
    pub(crate) fn error_weights(self) -> Option<&'static [f64]> {
        match self {
            Pair::Bs3 => Some(&BS3_E),
            Pair::Dopri5 => Some(&DP5_E),
            Pair::Dop853 => None,
        }
    }

    /// The dense output as a polynomial over the stages (and the derivative at the end):
    /// y(t₀ + θ·h) = y₀ + h·Σₖ kₖ·Σⱼ P[k][j]·θ^(j+1); `None` for DOP853, which evaluates three
    /// stages more for its own.
    pub(crate) fn dense_weights(self) -> Option<&'static [&'static [f64]]> {
        match self {
            Pair::Bs3 => Some(&BS3_P),
            Pair::Dopri5 => Some(&DP5_P),
            Pair::Dop853 => None,
        }
    }
    pub(crate) fn stage_count(self) -> usize {
        match self {
            Pair::Bs3 => 3,
            Pair::Dopri5 => 6,
            Pair::Dop853 => 12,
        }
    }

    pub(crate) fn a(self, s: usize) -> &'static [f64] {
        match self {
            Pair::Bs3 => BS3_A[s],
            Pair::Dopri5 => DP5_A[s],
            Pair::Dop853 => DOP853_A[s],
        }
    }

    pub(crate) fn c(self, s: usize) -> f64 {
        match self {
            Pair::Bs3 => BS3_C[s],
            Pair::Dopri5 => DP5_C[s],
            Pair::Dop853 => DOP853_C[s],
        }
    }

    /// The weights of the propagating method.
    pub(crate) fn b(self) -> &'static [f64] {
        match self {
            Pair::Bs3 => &BS3_B,
            Pair::Dopri5 => &DP5_B,
            Pair::Dop853 => DOP853_A[12],
        }
    }
}

pub(super) const BS3_C: [f64; 3] = [0.0, 1.0 / 2.0, 3.0 / 4.0];
pub(super) const BS3_A: [&[f64]; 3] = [&[], &[1.0 / 2.0], &[0.0, 3.0 / 4.0]];
pub(super) const BS3_B: [f64; 3] = [2.0 / 9.0, 1.0 / 3.0, 4.0 / 9.0];
/// The third-order weights less the second-order ones (7/24, 1/4, 1/3, 1/8), over the three
/// stages and the derivative at the end.
pub(super) const BS3_E: [f64; 4] = [2.0 / 9.0 - 7.0 / 24.0, 1.0 / 12.0, 1.0 / 9.0, -1.0 / 8.0];
/// The cubic Hermite interpolant of the step's ends, written over the stages: the derivative
/// at the start is the first stage and the one at the end the last, and y₁ − y₀ = h·Σ bⱼ kⱼ.
pub(super) const BS3_P: [&[f64]; 4] = [
    &[1.0, 3.0 * BS3_B[0] - 2.0, 1.0 - 2.0 * BS3_B[0]],
    &[0.0, 3.0 * BS3_B[1], -2.0 * BS3_B[1]],
    &[0.0, 3.0 * BS3_B[2], -2.0 * BS3_B[2]],
    &[0.0, -1.0, 1.0],
];

pub(super) const DP5_C: [f64; 6] = [0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0];
pub(super) const DP5_A: [&[f64]; 6] = [
    &[],
    &[1.0 / 5.0],
    &[3.0 / 40.0, 9.0 / 40.0],
    &[44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0],
    &[19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0],
    &[9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0],
];
pub(super) const DP5_B: [f64; 6] =
    [35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0];
/// The difference between the fifth- and fourth-order weights, over the 7 stages.
pub(super) const DP5_E: [f64; 7] = [
    -71.0 / 57600.0,
    0.0,
    71.0 / 16695.0,
    -71.0 / 1920.0,
    17253.0 / 339200.0,
    -22.0 / 525.0,
    1.0 / 40.0,
];
/// Shampine's quartic dense output: y(t0 + x h) = y0 + h Σ_k K_k Σ_j P[k][j] x^(j+1).
pub(super) const DP5_P: [&[f64]; 7] = [
    &[
        1.0,
        -8048581381.0 / 2820520608.0,
        8663915743.0 / 2820520608.0,
        -12715105075.0 / 11282082432.0,
    ],
    &[0.0, 0.0, 0.0, 0.0],
    &[
        0.0,
        131558114200.0 / 32700410799.0,
        -68118460800.0 / 10900136933.0,
        87487479700.0 / 32700410799.0,
    ],
    &[
        0.0,
        -1754552775.0 / 470086768.0,
        14199869525.0 / 1410260304.0,
        -10690763975.0 / 1880347072.0,
    ],
    &[
        0.0,
        127303824393.0 / 49829197408.0,
        -318862633887.0 / 49829197408.0,
        701980252875.0 / 199316789632.0,
    ],
    &[0.0, -282668133.0 / 205662961.0, 2019193451.0 / 616988883.0, -1453857185.0 / 822651844.0],
    &[0.0, 40617522.0 / 29380423.0, -110615467.0 / 29380423.0, 69997945.0 / 29380423.0],
];

#[allow(clippy::excessive_precision)]
pub(super) const DOP853_C: [f64; 16] = [
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
    1.0,
    0.1,
    0.2,
    0.777777777777777777777777777778,
];

/// Rows of the DOP853 tableau; row 12 holds the eighth-order weights b, rows 13–15 the
/// stages of the dense output.
#[allow(clippy::excessive_precision)]
pub(super) const DOP853_A: [&[f64]; 16] = [
    &[],
    &[5.26001519587677318785587544488e-2],
    &[1.97250569845378994544595329183e-2, 5.91751709536136983633785987549e-2],
    &[2.95875854768068491816892993775e-2, 0.0, 8.87627564304205475450678981324e-2],
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
    &[
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
    ],
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

/// The third-order weights: the 3rd-order error estimate is (b − bhh)·K.
#[allow(clippy::excessive_precision)]
pub(super) const DOP853_BHH: [f64; 12] = {
    let mut b = [0.0; 12];
    b[0] = 0.244094488188976377952755905512;
    b[8] = 0.733846688281611857341361741547;
    b[11] = 0.220588235294117647058823529412e-1;
    b
};

#[allow(clippy::excessive_precision)]
pub(super) const DOP853_E5: [f64; 12] = [
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

#[allow(clippy::excessive_precision)]
pub(super) const DOP853_D: [[f64; 16]; 4] = [
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
