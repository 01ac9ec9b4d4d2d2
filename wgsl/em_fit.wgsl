// Lobe fit, pass 2 of 2 (docs/design.md section 6): one workgroup per listed splat fits K lobes to
// the directions of the photons within R of its center, on its front side and inside a slab
// around its plane, by weighted EM with a fixed iteration count from constant initial lobes.
//
// Work split: the splat's candidates are the rows of bin cells around it (wgsl/shared/bins);
// invocation t takes every WG-th candidate, t first, in row order. The first CACHE_SLOTS / WG
// photons it accepts stay in workgroup memory (direction, weight; for sparse EM the first
// FROZEN also keep their responsibilities in private memory); any further ones are re-read
// and re-tested from the binned list on every pass, so a splat may have any number of
// photons and none is dropped. Each pass adds the invocation's photons into private sums in
// that fixed order; the sums of the invocations then add up in a fixed order too, so the
// result is deterministic: by a butterfly of subgroup shuffles where the device has subgroups
// that hold the workgroup (the `subgroups` variant: no workgroup memory, no barrier; llvmpipe
// fits 1.3x faster), else one column per invocation in workgroup memory and two barriers. Every invocation then runs the same M-step on the same totals.
//
// Bounded cost (em.fit_candidates > 0): a fitted splat with more candidates than that visits
// only every s-th of them in its EM passes and its final per-lobe sums, s = ceil(candidates /
// fit_candidates), each weighted s: an even, deterministic subset (the candidates lie in bin
// order, the order of space) whose sums estimate the whole set's, so the fit's time is bounded
// by splats, not photons. Its irradiance still sums every photon: the final pass adds them all
// in a loop of its own that only tests position and adds power, and the lobes' RGB irradiance
// is scaled per channel to that total. With s = 1 nothing changes.
//
// Passes: `iterations` EM passes (E-step + sums for the M-step), then one final pass with the
// fitted lobes: RGB irradiance per lobe, total irradiance, and the log-likelihood.
// Splats listed without the fit bit (not glossy) run only the final pass with no lobes.
//
// Pruning (em.prune > 0): from iteration PRUNE_FROM on, some E-steps (the next after a drop,
// else every PRUNE_PERIOD-th) also sum for each lobe k the log-likelihood the mixture would lose without it, sum w log(p / p_k) with
// p_k = (p - pi_k f_k) / (1 - pi_k) the mixture without k, renormalized: that is
// sum w (log(1 - pi_k) - log(1 - h_k)) in the responsibilities h, with 1 - h_k and 1 - pi_k
// added up from the other lobes (no cancellation when lobe k holds a photon alone).
// Rescaled to unit mean weight, the smallest loss is set against the BIC penalty
// PRUNE_PENALTY ln(1 + n) for n photons; a lobe under it is dropped after that iteration's
// M-step (one a pass, at most em.prune), and the iterations left refit the others to its
// photons (after a full E-step: sparse EM's frozen responsibilities knew the dropped lobe).
// The loss leaves the others as they were, so (for an EM step that raises the likelihood) it
// bounds the loss after the refit from above: a lobe is dropped only when the photons do not
// need it, though a cluster fitted by two lobes side by side may keep both. Dropped lobes get
// responsibility 0 and hand over between dispatches with sharpness 0; the lobes kept are
// written first, in order, so `light.lobes` counts them.
// Gathered samples (em.gathered > 0, docs/design.md section 6): the candidates of a fitted splat
// are then the em.gathered samples final gathering cast from its centre, in one row at
// (index - em.list_first) * gathered for fit-list entry index (the host dispatches the list a
// batch at a time), in the buffer bound as bin_power: radiance, and the direction's octahedral
// bits. None is tested for position, each weighs its radiance, and em.inv_area is
// pi / em.gathered, so that the sums estimate irradiance as the photons' do. Splats not fitted
// take no part: the photon dispatch before (with EM_DEFER_FIT, which gave the fitted splats
// only their irradiance) left their light. bin_geom and cell_start are not read.
// The host may split the iterations over several dispatches (see EmParams) to keep each
// invocation's loops under llvmpipe's limit; the mixture waits in the lobe buffer between.
// CPU mirror: src/cpu/em_fit.rs.

// #import types
// #import dispatch
// #import bins
// #import octahedral
// #import lobes

@group(0) @binding(0) var<uniform> em: EmParams;
@group(0) @binding(1) var<uniform> bins: BinParams;
// #paged
@group(0) @binding(2) var<storage, read> splats: array<Splat>;
@group(0) @binding(3) var<storage, read> fit_list: array<vec2<u32>>;
@group(0) @binding(4) var<storage, read> cell_start: array<u32>;
// #paged
@group(0) @binding(5) var<storage, read> bin_geom: array<BinnedPhoton>;
// #paged
@group(0) @binding(6) var<storage, read> bin_power: array<vec4<f32>>;
// #paged
@group(0) @binding(7) var<storage, read_write> lobes: array<Lobe>;
// #paged
@group(0) @binding(8) var<storage, read_write> light: array<SplatLight>;

// Lobes per splat and lobe family, fixed when the pipeline is made (the host passes
// EmParams.lobes and .family): loops over the lobes then have a known count, unroll, and keep
// the per-lobe arrays in registers; on llvmpipe that is several times faster.
override LOBES: u32 = 5u;
override FAMILY: u32 = 0u;
// Sparse EM (the EM_SPARSE flag), fixed per pipeline too: without it the frozen
// responsibilities and their stores vanish from the compiled code (13 % on llvmpipe).
override SPARSE: bool = false;

// Invocations per splat: the host picks 8 on llvmpipe (one SIMD8 subgroup, so barriers cost
// almost nothing; 32 ran at half the speed) and 32 elsewhere (a warp), and passes the same in
// EmParams.workgroup_size for the CPU mirror. Sums then run in a fixed order per device.
override WG: u32 = 32u;
const MAX_WG: u32 = 32u;
// Accepted photons kept per workgroup, CACHE_SLOTS / WG per invocation (slot c of invocation
// t at c * WG + t), in what `partial` leaves of WebGPU's 16 KiB. Workgroup memory, because
// llvmpipe turns a private array indexed per invocation into a select over every element;
// this cache made the fit 2x faster there than 8 private slots did.
const CACHE_SLOTS: u32 = 512u;
// Cached photons per invocation whose responsibilities sparse EM keeps (private memory).
const FROZEN: u32 = 8u;
// The slot of a photon that is not cached.
const NOT_CACHED: u32 = 0xffffffffu;
// The log weight of a dropped lobe: its responsibilities come out exactly 0.
const DROPPED_LOG: f32 = -3.0e38;
// Floor of 1 - h in a loss sum: a photon only the lobe explains costs 69 nats without it.
const REST_MIN: f32 = 1e-30;
// Sums: [0] sum w log p, [1] sum w, [2] photon count, [3..6) sum of RGB power, then six per
// lobe from LOBE_SUMS: EM passes sum w h, w h stat, w h w (3) and, when pruning, the
// loss sum -w log(1 - h); the final pass sums h RGB (3).
const SUM_LOG: u32 = 0u;
const SUM_WEIGHT: u32 = 1u;
const SUM_COUNT: u32 = 2u;
const SUM_RGB: u32 = 3u;
const LOBE_SUMS: u32 = 6u;
const LOBE_SLOTS: u32 = 6u;
const LOBE_LOSS: u32 = 5u;
const SUMS: u32 = 54u;
const PASS_EM: u32 = 0u;
const PASS_FINAL: u32 = 1u;

var<workgroup> shared_entry: vec2<u32>;
var<workgroup> shared_drop: u32;
var<workgroup> cache_dir: array<vec4<f32>, CACHE_SLOTS>;
var<workgroup> cache_index: array<u32, CACHE_SLOTS>;

// The splat (the same in every invocation).
var<private> center: vec3<f32>;
var<private> normal: vec3<f32>;
var<private> slab: f32;
// False for a splat that only gathers its irradiance.
var<private> fitting: bool;
// The mixture (identical in every invocation) and what the E-step derives from it.
var<private> mix_axis: array<vec3<f32>, MAX_LOBES>;
var<private> mix_sharpness: array<f32, MAX_LOBES>;
var<private> mix_weight: array<f32, MAX_LOBES>;
var<private> mix_mirror: array<vec3<f32>, MAX_LOBES>;
var<private> mix_log: array<f32, MAX_LOBES>;
// The lobes not dropped by pruning, one bit each.
var<private> alive: u32;
// One photon's responsibilities and per-lobe statistics (for frozen lobes: h * stat).
var<private> resp: array<f32, MAX_LOBES>;
var<private> stat: array<f32, MAX_LOBES>;
var<private> acc: array<f32, SUMS>;
// Sparse EM: the frozen responsibilities (and h * stat) of the first FROZEN cached photons,
// and the lobes the last e_step left frozen, one bit each.
var<private> frozen_h: array<array<f32, MAX_LOBES>, FROZEN>;
var<private> frozen_hx: array<array<f32, MAX_LOBES>, FROZEN>;
var<private> frozen_mask: u32;
// This invocation's photons: how many are cached, then where streaming resumes.
var<private> cached: u32;
var<private> streaming: bool;
var<private> resume_row: u32;
var<private> resume_j: u32;
var<private> resume_offset: u32;
// This splat's candidate stride s (see "Bounded cost") and WG * s, an invocation's step.
var<private> stride: u32;
var<private> step: u32;
// With gathered samples, this splat's first.
var<private> sample_first: u32;

// The splat's candidate rows: its bin rows, or the one row of its gathered samples.
fn row_count(box: BinBox) -> u32 {
    return select(bin_row_count(box), 1u, em.gathered > 0u);
}

// Candidates [x, y) of row r.
fn row_span(box: BinBox, r: u32) -> vec2<u32> {
    if em.gathered > 0u {
        return vec2<u32>(sample_first, sample_first + em.gathered);
    }
    let row = bin_row(box, r, bins);
    return vec2<u32>(cell_start[row.x], cell_start[row.y]);
}

// First candidate of row [begin, ..) for invocation `lid`, whose candidates are those with
// (offset + position in row) = lid * stride mod WG * stride (every stride-th, dealt round).
fn first_in_row(begin: u32, offset: u32, lid: u32) -> u32 {
    return begin + (lid * stride + step - offset % step) % step;
}

struct Candidate {
    ok: bool,
    dir: vec3<f32>,
    weight: f32,
}

fn accept(j: u32) -> Candidate {
    var c: Candidate;
    if em.gathered > 0u {
        let sample = bin_power_at(j);
        c.dir = oct_decode(bitcast<u32>(sample.w));
        c.weight = photon_weight(sample.xyz) * f32(stride);
        c.ok = c.weight > 0.0;
        return c;
    }
    let g = bin_geom_at(j);
    let d = g.position - center;
    // Most candidates fail on position: the direction and the power only load for the rest.
    c.ok = dot(d, d) <= em.radius2 && abs(dot(d, normal)) <= slab;
    if c.ok {
        let power = bin_power_at(j);
        c.dir = oct_decode(g.direction);
        c.ok = dot(c.dir, normal) > 0.0 && dot(surface_decode(power.w), normal) >= SURFACE_COS_MIN;
        c.weight = photon_weight(power.xyz) * f32(stride);
    }
    return c;
}

fn prepare_mixture() {
    for (var k = 0u; k < LOBES; k++) {
        mix_mirror[k] = mirror_axis(normal, mix_axis[k]);
        mix_log[k] = max(log(max(mix_weight[k], 1e-35)), LOG_WEIGHT_MIN)
            + lobe_log_norm(FAMILY, normal, mix_axis[k], mix_sharpness[k]);
        if (alive & (1u << k)) == 0u {
            mix_log[k] = DROPPED_LOG;
        }
    }
}

// Responsibilities of photon `w` into `resp` (and `stat`); returns log p(w) of the mixture
// when every lobe was evaluated. With `sparse`, lobes whose frozen responsibility for cached
// photon `slot` (if under FROZEN) is under the threshold keep it (and h * stat), and the
// others share the rest.
fn e_step(w: vec3<f32>, slot: u32, sparse: bool, full: bool) -> f32 {
    let use_frozen = sparse && !full && slot < FROZEN;
    frozen_mask = 0u;
    var frozen_sum = 0.0;
    var m = -3.0e38;
    for (var k = 0u; k < LOBES; k++) {
        if use_frozen && frozen_h[slot][k] < SPARSE_THRESHOLD {
            frozen_mask |= 1u << k;
            frozen_sum += frozen_h[slot][k];
            continue;
        }
        stat[k] = lobe_stat(FAMILY, normal, mix_axis[k], mix_mirror[k], w);
        resp[k] = mix_log[k] + lobe_exponent(FAMILY, mix_sharpness[k], stat[k]);
        m = max(m, resp[k]);
    }
    var s = 0.0;
    for (var k = 0u; k < LOBES; k++) {
        if (frozen_mask & (1u << k)) == 0u {
            resp[k] = exp(resp[k] - m);
            s += resp[k];
        }
    }
    let scale = (1.0 - frozen_sum) / s;
    for (var k = 0u; k < LOBES; k++) {
        if (frozen_mask & (1u << k)) != 0u {
            resp[k] = frozen_h[slot][k];
            stat[k] = frozen_hx[slot][k];
        } else {
            resp[k] *= scale;
            if sparse && slot < FROZEN {
                frozen_h[slot][k] = resp[k];
                frozen_hx[slot][k] = resp[k] * stat[k];
            }
        }
    }
    return m + log(s);
}

// Adds one photon to this invocation's sums (with `losses`, pruning's too).
fn absorb(w: vec3<f32>, weight: f32, index: u32, slot: u32, kind: u32, sparse: bool, full: bool,
          losses: bool) {
    acc[SUM_WEIGHT] += weight;
    if kind == PASS_FINAL {
        let power = bin_power_at(index).xyz;
        // A subset's final pass leaves the count and the irradiance to irradiance_pass.
        if stride == 1u {
            acc[SUM_COUNT] += 1.0;
            acc[SUM_RGB] += power.x;
            acc[SUM_RGB + 1u] += power.y;
            acc[SUM_RGB + 2u] += power.z;
        }
        if !fitting {
            return;
        }
        acc[SUM_LOG] += weight * e_step(w, slot, false, true);
        for (var k = 0u; k < LOBES; k++) {
            let o = LOBE_SUMS + LOBE_SLOTS * k;
            acc[o] += resp[k] * power.x;
            acc[o + 1u] += resp[k] * power.y;
            acc[o + 2u] += resp[k] * power.z;
        }
        return;
    }
    acc[SUM_COUNT] += 1.0;
    e_step(w, slot, sparse, full);
    for (var k = 0u; k < LOBES; k++) {
        let o = LOBE_SUMS + LOBE_SLOTS * k;
        let wh = weight * resp[k];
        let frozen = (frozen_mask & (1u << k)) != 0u;
        acc[o] += wh;
        acc[o + 1u] += select(wh * stat[k], weight * stat[k], frozen);
        acc[o + 2u] += wh * w.x;
        acc[o + 3u] += wh * w.y;
        acc[o + 4u] += wh * w.z;
        if losses {
            var rest = 0.0;
            for (var j = 0u; j < LOBES; j++) {
                if j != k {
                    rest += resp[j];
                }
            }
            acc[o + LOBE_LOSS] -= weight * log(max(rest, REST_MIN));
        }
    }
}

// The invocation's first `CACHE_SLOTS / WG` accepted photons into the cache; notes where the
// rest begin.
fn gather(lid: u32, box: BinBox) {
    let capacity = CACHE_SLOTS / WG;
    cached = 0u;
    streaming = false;
    var offset = 0u;
    for (var r = 0u; r < row_count(box); r++) {
        let span = row_span(box, r);
        let begin = span.x;
        let end = span.y;
        for (var j = first_in_row(begin, offset, lid); j < end; j += step) {
            let c = accept(j);
            if !c.ok {
                continue;
            }
            if cached == capacity {
                streaming = true;
                resume_row = r;
                resume_j = j;
                resume_offset = offset;
                return;
            }
            cache_dir[cached * WG + lid] = vec4<f32>(c.dir, c.weight);
            cache_index[cached * WG + lid] = j;
            cached += 1u;
        }
        offset += end - begin;
    }
}

// One pass over this invocation's photons, cached ones first, into fresh private sums.
fn photon_pass(lid: u32, box: BinBox, kind: u32, sparse: bool, full: bool, losses: bool) {
    for (var q = 0u; q < SUMS; q++) {
        acc[q] = 0.0;
    }
    for (var c = 0u; c < cached; c++) {
        let d = cache_dir[c * WG + lid];
        absorb(d.xyz, d.w, cache_index[c * WG + lid], c, kind, sparse, full, losses);
    }
    if !streaming {
        return;
    }
    var offset = resume_offset;
    for (var r = resume_row; r < row_count(box); r++) {
        let span = row_span(box, r);
        let begin = span.x;
        let end = span.y;
        var j = select(first_in_row(begin, offset, lid), resume_j, r == resume_row);
        for (; j < end; j += step) {
            let c = accept(j);
            if c.ok {
                absorb(c.dir, c.weight, j, NOT_CACHED, kind, sparse, full, losses);
            }
        }
        offset += end - begin;
    }
}

// Every photon of this invocation (every WG-th candidate, whatever the stride) into the
// count and RGB sums: a subset's final pass (see "Bounded cost").
fn irradiance_pass(lid: u32, box: BinBox) {
    var offset = 0u;
    for (var r = 0u; r < row_count(box); r++) {
        let span = row_span(box, r);
        let begin = span.x;
        let end = span.y;
        for (var j = begin + (lid + WG - offset % WG) % WG; j < end; j += WG) {
            if accept(j).ok {
                let power = bin_power_at(j).xyz;
                acc[SUM_COUNT] += 1.0;
                acc[SUM_RGB] += power.x;
                acc[SUM_RGB + 1u] += power.y;
                acc[SUM_RGB + 2u] += power.z;
            }
        }
        offset += end - begin;
    }
}

// The candidates of the splat's rows (fit_select counts the same bin rows).
fn candidate_count(box: BinBox) -> u32 {
    var n = 0u;
    for (var r = 0u; r < row_count(box); r++) {
        let span = row_span(box, r);
        n += span.y - span.x;
    }
    return n;
}

// The lightest live lobe whose loss (see "Pruning" above) is under the penalty, after an EM
// pass's `reduce` and before its M-step; LOBES when there is none, or only one lobe lives.
// The lightest, not the one of least loss: near-identical lobes have losses equal but for
// rounding, which would pick a different one on each device; weights part less easily.
fn weakest_lobe() -> u32 {
    let n = sum(SUM_COUNT);
    let total_weight = sum(SUM_WEIGHT);
    var weakest = LOBES;
    if countOneBits(alive) < 2u || n < 1.0 || total_weight <= 0.0 {
        return weakest;
    }
    let penalty = PRUNE_PENALTY * log(1.0 + n);
    var lightest = 2.0;
    for (var k = 0u; k < LOBES; k++) {
        if (alive & (1u << k)) == 0u {
            continue;
        }
        var rest_weight = 0.0;
        for (var j = 0u; j < LOBES; j++) {
            if j != k && (alive & (1u << j)) != 0u {
                rest_weight += mix_weight[j];
            }
        }
        let loss = sum(LOBE_SUMS + LOBE_SLOTS * k + LOBE_LOSS) * (n / total_weight)
            + n * log(max(rest_weight, REST_MIN));
        if loss < penalty && mix_weight[k] < lightest {
            lightest = mix_weight[k];
            weakest = k;
        }
    }
    return weakest;
}

// Drops lobe k and renormalizes the others' weights.
fn drop_lobe(k: u32) {
    alive &= ~(1u << k);
    var rest_weight = 0.0;
    for (var j = 0u; j < LOBES; j++) {
        if (alive & (1u << j)) != 0u {
            rest_weight += mix_weight[j];
        }
    }
    for (var j = 0u; j < LOBES; j++) {
        mix_weight[j] = select(0.0, mix_weight[j] / rest_weight, (alive & (1u << j)) != 0u);
    }
}

// #ifdef subgroups
// Fixed-order sum of the first `count` sums over the invocations, left in every invocation's
// `acc`: step by step, each adds its partner's value at distance WG/2, WG/4, ..., 1 (a + b
// equals b + a in floating point, so all end with the same bits).
fn reduce(lid: u32, count: u32) {
    for (var q = 0u; q < count; q++) {
        var v = acc[q];
        for (var step = WG / 2u; step > 0u; step /= 2u) {
            v += subgroupShuffleXor(v, step);
        }
        acc[q] = v;
    }
}

// Sum q of the workgroup, after `reduce`.
fn sum(q: u32) -> f32 {
    return acc[q];
}
// #else
// Sums per round of `reduce`: all SUMS columns of MAX_WG invocations would not fit beside the
// photon cache.
const PARTIAL_COLUMNS: u32 = 32u;
var<workgroup> partial: array<array<f32, PARTIAL_COLUMNS>, MAX_WG>;
var<workgroup> total: array<f32, SUMS>;

// Fixed-order sum of the first `count` sums over the invocations into `total`: column by
// column, invocation 0 first, PARTIAL_COLUMNS columns a round.
fn reduce(lid: u32, count: u32) {
    for (var first = 0u; first < count; first += PARTIAL_COLUMNS) {
        let columns = min(count - first, PARTIAL_COLUMNS);
        for (var q = 0u; q < columns; q++) {
            partial[lid][q] = acc[first + q];
        }
        workgroupBarrier();
        for (var q = lid; q < columns; q += WG) {
            var s = 0.0;
            for (var t = 0u; t < WG; t++) {
                s += partial[t][q];
            }
            total[first + q] = s;
        }
        workgroupBarrier();
    }
}

fn sum(q: u32) -> f32 {
    return total[q];
}
// #endif

@compute @workgroup_size(WG)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let index = em.list_first + linear_workgroup(wg, num_wg);
    if index >= em.active_count {
        return;
    }
    if lid == 0u {
        shared_entry = fit_list[index];
    }
    let listed = workgroupUniformLoad(&shared_entry);
    let entry = listed.x;
    let splat_index = entry & ~FIT_BIT;
    let fit = (entry & FIT_BIT) != 0u && (em.flags & EM_DEFER_FIT) == 0u;
    if em.gathered > 0u && !fit {
        return;
    }
    sample_first = (index - em.list_first) * em.gathered;
    // The splat's lobes in the lobe buffer, which holds the fitted splats' alone.
    let first = listed.y * em.lobes;
    let s = splats_at(splat_index);
    center = s.center;
    normal = s.normal;
    slab = em.slab * s.radius;
    fitting = fit;
    // Diffuse splats run no iterations; their only pass comes with the last dispatch.
    let begin = select(em.iterations, em.iteration_begin, fit);
    let end = select(em.iterations, em.iteration_end, fit);
    let last = em.iteration_end == em.iterations;
    if !last && !fit {
        return;
    }
    let f = frame_of(normal);
    for (var k = 0u; k < LOBES; k++) {
        if begin == 0u {
            mix_axis[k] = initial_axis(f, k, LOBES);
            mix_sharpness[k] = initial_sharpness(FAMILY);
            mix_weight[k] = 1.0 / f32(LOBES);
        } else {
            let l = lobes_at(first + k);
            mix_axis[k] = l.axis;
            mix_sharpness[k] = l.sharpness;
            mix_weight[k] = l.weight;
        }
    }
    // A lobe handed over with sharpness 0 was dropped.
    alive = 0u;
    for (var k = 0u; k < LOBES; k++) {
        if mix_sharpness[k] > 0.0 {
            alive |= 1u << k;
        }
    }
    let box = bin_box(center, em.radius, bins);
    stride = 1u;
    if fit && em.fit_candidates > 0u {
        stride = max(1u, (candidate_count(box) + em.fit_candidates - 1u) / em.fit_candidates);
    }
    step = WG * stride;
    gather(lid, box);
    let sparse = SPARSE;
    let sums = LOBE_SUMS + LOBE_SLOTS * LOBES;

    var dropped_one = false;
    // The next iteration whose E-step sums the losses (see PRUNE_PERIOD); each dispatch starts
    // with one.
    var next_check = max(begin, PRUNE_FROM);
    for (var it = begin; it < end; it++) {
        prepare_mixture();
        // A dispatch starts with no frozen responsibilities, hence a full update; so does the
        // pass after a drop.
        let full = it % SPARSE_PERIOD == 0u || it == begin || dropped_one;
        // Until em.prune lobes are gone.
        let pruning = it == next_check && LOBES - countOneBits(alive) < em.prune;
        photon_pass(lid, box, PASS_EM, sparse, full, pruning);
        reduce(lid, sums);
        if pruning {
            if lid == 0u {
                shared_drop = weakest_lobe();
            }
        }
        let weakest = select(LOBES, workgroupUniformLoad(&shared_drop), pruning);
        let live = countOneBits(alive);
        for (var k = 0u; k < LOBES; k++) {
            if (alive & (1u << k)) == 0u {
                continue;
            }
            let o = LOBE_SUMS + LOBE_SLOTS * k;
            let old = LobeFit(mix_axis[k], mix_sharpness[k], mix_weight[k]);
            let s2 = vec3<f32>(sum(o + 2u), sum(o + 3u), sum(o + 4u));
            let next = m_step(FAMILY, em.flags, live, sum(o), sum(o + 1u), s2,
                              sum(SUM_WEIGHT), sum(SUM_COUNT), old);
            mix_axis[k] = next.axis;
            mix_sharpness[k] = next.sharpness;
            mix_weight[k] = next.weight;
        }
        dropped_one = weakest < LOBES;
        if dropped_one {
            drop_lobe(weakest);
        }
        if pruning {
            next_check = it + select(PRUNE_PERIOD, 1u, dropped_one);
        }
    }

    if !last {
        if lid < LOBES && fit {
            let sharpness = select(0.0, mix_sharpness[lid], (alive & (1u << lid)) != 0u);
            let lobe = Lobe(mix_axis[lid], sharpness, vec3<f32>(0.0), mix_weight[lid]);
            lobes_put(first + lid, lobe);
        }
        return;
    }
    prepare_mixture();
    photon_pass(lid, box, PASS_FINAL, false, true, false);
    if stride > 1u {
        irradiance_pass(lid, box);
    }
    reduce(lid, sums);
    let photons = u32(sum(SUM_COUNT));
    // A subset's lobes share the irradiance of every photon, channel by channel.
    var share = vec3<f32>(1.0);
    if stride > 1u {
        var lobe_rgb = vec3<f32>(0.0);
        for (var k = 0u; k < LOBES; k++) {
            let o = LOBE_SUMS + LOBE_SLOTS * k;
            lobe_rgb += vec3<f32>(sum(o), sum(o + 1u), sum(o + 2u));
        }
        let rgb = vec3<f32>(sum(SUM_RGB), sum(SUM_RGB + 1u), sum(SUM_RGB + 2u));
        share = select(vec3<f32>(0.0), rgb / lobe_rgb, lobe_rgb > vec3<f32>(0.0));
    }
    let written = select(0u, countOneBits(alive), photons > 0u && fit);
    // Invocation t writes the t-th live lobe into slot t.
    var slot = 0u;
    for (var k = 0u; k < LOBES; k++) {
        if (alive & (1u << k)) == 0u {
            continue;
        }
        if slot == lid && lid < written {
            let o = LOBE_SUMS + LOBE_SLOTS * k;
            let irradiance = vec3<f32>(sum(o), sum(o + 1u), sum(o + 2u)) * share * em.inv_area;
            let lobe = Lobe(mix_axis[k], mix_sharpness[k], irradiance, mix_weight[k]);
            lobes_put(first + lid, lobe);
        }
        slot += 1u;
    }
    if lid == 0u {
        var out: SplatLight;
        out.irradiance = vec3<f32>(sum(SUM_RGB), sum(SUM_RGB + 1u), sum(SUM_RGB + 2u))
            * em.inv_area;
        out.photons = photons;
        out.log_likelihood = sum(SUM_LOG);
        out.weight = sum(SUM_WEIGHT);
        out.lobes = written;
        out.first_lobe = select(0u, first, fit);
        light_put(splat_index, out);
    }
}
