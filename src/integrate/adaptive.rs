//! The adaptive integrator's settings and its Gauss-Kronrod table: one definition for both of its twins, the
//! f64 reference (`reference::adaptive`, `adaptive_smooth`, `adaptive_curves`, where the method is described)
//! and the WGSL passes, into whose modules `gpu::shaders::shared_constants` writes them. Neither twin declares
//! them again, and the GPU's iteration budget (`gpu::field_pass`) counts with these.

// The Gauss-Kronrod pairs and the choice of one.

/// Gauss-Kronrod pairs on [-1, 1]: the Gauss-Legendre rule of `n` nodes and the Kronrod rule of `2n + 1` nodes
/// that contains it, for `n` in `KRONROD_ORDERS`. Rule `k` is `n + 1` rows from `KRONROD_START[k]`: each a node
/// `x >= 0` (the first is 0) with its Kronrod weight and its Gauss weight (0 where `x` is a Kronrod node only). The
/// difference of the two rules on an interval bounds the error of the Kronrod value there, which the integrator
/// refines until it is within its share of the tolerance (`integrate_panel`). Computed to 60 digits (the
/// Stieltjes polynomial's roots, then the weights from the moments) and printed to 17; `reference::adaptive`'s tests check
/// that the Kronrod rule of `n` is exact to degree `3n + 1` and the Gauss rule to `2n - 1`. The WGSL twin's table is
/// written from this one (`gpu::shaders::shared_constants`).
pub const KRONROD_ORDERS: [u32; 7] = [3, 4, 5, 6, 7, 8, 10];
pub const KRONROD_START: [usize; 7] = [0, 4, 9, 15, 22, 30, 39];

#[allow(clippy::excessive_precision)]
pub const KRONROD: [(f64, f64, f64); 50] = [
    (0.0, 0.45091653865847414, 0.88888888888888889), // 3
    (0.43424374934680256, 0.40139741477596222, 0.0), // 3
    (
        0.77459666924148338,
        0.26848808986833344,
        0.55555555555555556,
    ), // 3
    (0.96049126870802028, 0.10465622602646727, 0.0), // 3
    (0.0, 0.34644298189013636, 0.0),                 // 4
    (
        0.33998104358485626,
        0.32694918960145163,
        0.65214515486254614,
    ), // 4
    (0.64028621749630998, 0.26679834045228445, 0.0), // 4
    (
        0.86113631159405258,
        0.17005360533572273,
        0.34785484513745386,
    ), // 4
    (0.97656025073757311, 0.062977373665473015, 0.0), // 4
    (0.0, 0.28298741785749121, 0.56888888888888889), // 5
    (0.27963041316178319, 0.27284980191255892, 0.0), // 5
    (
        0.53846931010568309,
        0.24104033922864759,
        0.47862867049936647,
    ), // 5
    (0.75416672657084922, 0.18680079655649266, 0.0), // 5
    (
        0.90617984593866399,
        0.11523331662247339,
        0.23692688505618909,
    ), // 5
    (0.98408536009484246, 0.042582036751081833, 0.0), // 5
    (0.0, 0.24107258017346476, 0.0),                 // 6
    (
        0.23861918608319691,
        0.23377086411699441,
        0.46791393457269105,
    ), // 6
    (0.46311821247530461, 0.21320965227196228, 0.0), // 6
    (
        0.66120938646626451,
        0.18107199432313762,
        0.36076157304813861,
    ), // 6
    (0.82137334086502794, 0.13732060463444692, 0.0), // 6
    (
        0.93246951420315203,
        0.083694440446906626,
        0.17132449237917035,
    ), // 6
    (0.98870320261267886, 0.030396154119819769, 0.0), // 6
    (0.0, 0.20948214108472783, 0.41795918367346939), // 7
    (0.20778495500789847, 0.20443294007529889, 0.0), // 7
    (
        0.40584515137739717,
        0.19035057806478541,
        0.38183005050511894,
    ), // 7
    (0.58608723546769113, 0.1690047266392679, 0.0),  // 7
    (
        0.74153118559939444,
        0.14065325971552592,
        0.27970539148927667,
    ), // 7
    (0.86486442335976907, 0.10479001032225018, 0.0), // 7
    (
        0.94910791234275852,
        0.063092092629978553,
        0.12948496616886969,
    ), // 7
    (0.99145537112081264, 0.022935322010529225, 0.0), // 7
    (0.0, 0.18444640574469164, 0.0),                 // 8
    (0.1834346424956498, 0.18140002506803464, 0.36268378337836198), // 8
    (0.36070109792813196, 0.17207060855521131, 0.0), // 8
    (0.52553240991632899, 0.1566526061681884, 0.31370664587788729), // 8
    (0.67235407094515868, 0.13626310925517222, 0.0), // 8
    (
        0.79666647741362674,
        0.11164637082683961,
        0.22238103445337447,
    ), // 8
    (0.89412090684745642, 0.082482298931358331, 0.0), // 8
    (
        0.96028985649753623,
        0.049439395002139309,
        0.10122853629037626,
    ), // 8
    (0.99337987588171616, 0.017822383320710355, 0.0), // 8
    (0.0, 0.14944555400291691, 0.0),                 // 10
    (
        0.14887433898163121,
        0.14773910490133849,
        0.29552422471475287,
    ), // 10
    (0.2943928627014602, 0.14277593857706008, 0.0),  // 10
    (
        0.43339539412924719,
        0.13470921731147333,
        0.26926671930999636,
    ), // 10
    (0.56275713466860468, 0.12349197626206585, 0.0), // 10
    (
        0.67940956829902441,
        0.10938715880229764,
        0.21908636251598204,
    ), // 10
    (0.7808177265864169, 0.093125454583697606, 0.0), // 10
    (
        0.86506336668898451,
        0.075039674810919953,
        0.14945134915058059,
    ), // 10
    (0.93015749135570823, 0.054755896574351996, 0.0), // 10
    (
        0.97390652851717172,
        0.032558162307964727,
        0.066671344308688138,
    ), // 10
    (0.99565716302580808, 0.011694638867371874, 0.0), // 10
];

/// The Gauss-Kronrod pair for the scene's tolerance on B: a higher order for a finer tolerance, so that smooth
/// pieces pass the error test without refinement. B is scale free (coefficient over distance), and so is this
/// choice.
pub fn kronrod_order(tolerance: f64) -> u32 {
    match tolerance {
        t if t >= 1e-3 => 4,
        t if t >= 1e-4 => 5,
        t if t >= 1e-5 => 6,
        t if t >= 1e-6 => 7,
        t if t >= 1e-7 => 8,
        _ => 10,
    }
}

/// Index of `order` in `KRONROD_ORDERS` (the last for anything else).
pub fn kronrod_index(order: u32) -> usize {
    KRONROD_ORDERS
        .iter()
        .position(|&n| n == order)
        .unwrap_or(KRONROD_ORDERS.len() - 1)
}

// Panels and their refinement.

/// The longest stretch of u one panel (one Gauss-Kronrod pair before refinement) covers.
pub const U_PANEL: f64 = 4.0;

/// Most panels on one cut of a piece. This and the other settings here the WGSL twin uses are declared in it
/// from these definitions (`gpu::shaders::shared_constants`).
pub const MAX_GAUSS_PANELS: u32 = 8;

/// Levels of bisection of a panel at most: its smallest part is `2^-MAX_DEPTH` of it.
pub const MAX_DEPTH: u32 = 10;

/// Parts a term may refine beyond its panels at most (each refinement spends two more rules).
pub const MAX_REFINEMENTS: u32 = 24;

/// The refinements a term may spend with the pair of `order`: `COARSE_REFINEMENTS` with a coarse pair (lavapipe
/// stops a shader invocation after 65535 loop iterations, and a term's parts solved on the whole chain cost the
/// most), `MAX_REFINEMENTS` for a finer one.
pub fn refinement_budget(order: u32) -> u32 {
    if order <= COARSE_ORDER {
        COARSE_REFINEMENTS
    } else {
        MAX_REFINEMENTS
    }
}

/// The highest Gauss-Kronrod order that counts as coarse (the default tolerance's, and coarser ones'): a term
/// then refines at most `COARSE_REFINEMENTS` times and the kink search stops at `KINK_BRACKET`; a finer pair gets
/// `MAX_REFINEMENTS` and `FINE_KINK_BRACKET`.
pub const COARSE_ORDER: u32 = 5;
/// The refinements a term may spend with a coarse pair (`refinement_budget`).
pub const COARSE_REFINEMENTS: u32 = 8;

// Features and cuts.

/// Most features of one term: a torus's two ring passes and its axis, or a chain's two closest approaches and its
/// two ends.
pub const MAX_PEAKS: usize = 4;

/// Widest feature considered: beyond it the map is as good as uniform.
pub const MAX_WIDTH: f64 = 4.0;

/// Narrowest axis feature: a ray through the axis itself has a true kink there, which a map this narrow
/// resolves as well as any.
pub const MIN_AXIS_WIDTH: f64 = 1e-4;

/// Most kinks cut on one curve's ray. Sixteen: a chain's scan, sampled finer where the nearest point passes a joint,
/// filled eight with the figure 12 preset's cuts near its joint and dropped the rest (1.6e-3 of B lost).
pub const MAX_KINKS: usize = 16;

/// Cuts of a piece closer than this in u are merged (`cuts`).
pub const CUT_MERGE: f64 = 1e-6;

/// Ordinary cuts closer than this in u to a singular one are dropped (`cuts`).
pub const SINGULAR_MERGE: f64 = 1e-3;

// A curve chain's scan, jumps and kinks.

/// Intervals of the scan along a curve's ray, which finds its closest approaches and kinks.
pub const SCAN: u32 = 6;

/// How many times finer the scan samples an interval of a chain of several segments where the nearest point may
/// leave its segment and come back, or passes more than one event (the reference's `Survey::suspect`).
pub const SUB_SCAN: u32 = 8;

/// Another segment is a rival of the one the scan finds the nearest point on where its closest approach to the ray,
/// squared, is within this of the farthest the chain can be from the ray between two samples (a margin for the
/// rounding of both, in f32 on the GPU).
pub const RIVAL_MARGIN: f64 = 1.02;

/// A closest approach to the ray found segment by segment is the chain's where the chain's nearest point there is
/// at least this share of its distance squared (a little under 1: the two distances are rounded differently, and a
/// candidate another segment barely hides still marks where d^2 is least).
pub const EXACT_SLACK: f64 = 0.81;

/// How many of a chain's closest approaches to the ray, found segment by segment, are sampled to check they are
/// the chain's: the deepest, one more than are kept (`MINIMA`), for one another segment hides.
pub const EXACT_SAMPLES: u32 = 4;

/// How many closest approaches of a chain along one ray become peaks (each owning its piece of the ray). Three: a
/// ray can pass near both segments beside a joint and, past a jump within a segment, near the first again (a ray
/// with three lost 1.5e-2 of B with room for two).
pub const MINIMA: usize = 3;

/// Intervals of the scan along the ray of a curve in the continuous W form, which finds where its brightest point
/// jumps between parts of the chain (each sample a whole search: finer than `SCAN`, since two jumps within one
/// interval cancel out and go unseen).
pub const BRIGHT_SCAN: u32 = 24;

/// Bisections that place a cut where the brightest point passes the end of a piece (in its interpolated motion
/// between two samples of the scan): 2^-24 of a scan interval.
pub const CUT_BISECTIONS: u32 = 24;

/// A chain's nearest point jumps between two samples where it lands farther than this many times the distance
/// from where a smooth motion would have taken it.
pub const JUMP: f64 = 0.1;

/// Or where its chain parameter lands farther than this from where its rate would have taken it (`miss`).
pub const PARAM_JUMP: f64 = 0.05;

/// An interval whose miss lies between this share of `JUMP` and `JUMP` is looked at again at its middle: where the
/// nearest point races toward a jump (near a center of curvature), the average of the two ends' velocities can
/// carry it most of the way across the jump, so that the whole interval misses by less than `JUMP` while one of
/// its halves misses by more. (A wavy chain of seven segments: a jump of 0.077 in the chain parameter, missed at
/// 0.083 over a scan of 12, and B off by 1.75e-2 where the tracked segment then lost the nearest point.)
pub const SUSPECT_MISS: f64 = 0.25;

/// Most rounds of the kink search, each one or two probes. (Two are not enough: a kink misplaced by 5e-3 where W
/// steps across it costs 5e-4 on a ray of the mixed scene.)
pub const KINK_ROUNDS: u32 = 12;

/// The kink search stops when its bracket is this short (in t, the ray being 1 long).
pub const KINK_BRACKET: f64 = 1e-3;

/// How short the kink search's bracket gets with the pair of `order`: `KINK_BRACKET` with a coarse pair
/// (`COARSE_ORDER`), `FINE_KINK_BRACKET` with a finer one (a W step misplaced by 1e-3 costs about 3e-5 on the seven-weight preset).
pub fn kink_bracket(order: u32) -> f64 {
    if order <= COARSE_ORDER {
        KINK_BRACKET
    } else {
        FINE_KINK_BRACKET
    }
}
/// The kink search's shortest bracket with a pair finer than `COARSE_ORDER` (`kink_bracket`).
pub const FINE_KINK_BRACKET: f64 = 1e-5;

/// How far either side of its estimate a round of the kink search probes, relative to the bracket.
pub const KINK_PROBE: f64 = 0.05;

/// How close to an end of the chain (in its parameter) a nearest point counts as at it (`at`).
pub const END_SNAP: f64 = 1e-4;

/// Newton steps that refine a chain's closest approach from the scan, at most.
pub const PEAK_NEWTON: u32 = 2;

/// Newton stops once its step is this small against the peak's width (a broad peak needs no refinement: the map
/// is exact whatever its center, and a center off by a fraction of the width costs little accuracy).
pub const PEAK_SETTLED: f64 = 0.25;

/// Bisection rounds that find where a part's nearest segment changes (`split_at_switch`).
pub const SWITCH_ROUNDS: u32 = 24;

/// How far inside a part (a share of its length) `split_at_switch` looks at its ends' segments.
pub const SWITCH_INSET: f64 = 1e-3;

// A torus's ring, and the closed form of points and lines.

/// Newton steps that find a ring's closest approach, and the longest of them (in t).
pub const RING_NEWTON: u32 = 6;

pub const RING_STEP: f64 = 0.125;

/// Most cancellation the closed form of a point's or a line's term may suffer before the integrator takes it
/// numerically instead (`falloff_integral`'s `condition`): in f32 (the shader, which uses the same
/// bound) a term's error stays within about 2e-5 of it, measured over 200 000 random rays. Its cancellation grows
/// as the source nears the decay's pole at s = -beta (about 3.7 / z at `z = POLE_SERIES_REACH`), where the pole
/// series takes the term instead; what it still declines is rare.
pub const CLOSED_FORM_CONDITION: f64 = 16.0;

/// Where a point's or a line's term on a piece of the ray is summed as a series about the decay's pole
/// (`falloff_integral`): where the source lies within `z` of the pole, z the ratio of its distance from the pole
/// point `S - beta (E - S)` to the distance from there to the piece's start. There the closed form's two parts
/// grow as 1 / A^(3/2) (A the squared distance of source and pole) while their difference stays finite, so it
/// loses every digit to cancellation as the source reaches the pole (a line through the eye, the pole at the
/// papers' settings); the series converges as z^n. At this reach the closed form cancels at most about 12x.
pub const POLE_SERIES_REACH: f64 = 0.3;

/// Terms of the pole series in f64: `POLE_SERIES_REACH^32` is below 2e-17.
pub const POLE_SERIES_TERMS: u32 = 32;

/// Terms of the pole series in f32 (the shader): `POLE_SERIES_REACH^16` is below 5e-9.
pub const POLE_SERIES_TERMS_F32: u32 = 16;
