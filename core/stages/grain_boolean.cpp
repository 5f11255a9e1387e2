#include "core/stages/grain_boolean.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>

#include "core/parallel.h"
#include "core/simd.h"
#include "core/stages/grain.h"

namespace darkroom {

namespace {

const double kLn10 = std::log(10.0);
constexpr int kTableNodes = 301;           // net density step 0.01
constexpr double kCellLimitUm = 8.0;       // cells are at most this wide
constexpr double kFootprintReachSigmas = 5.0;
constexpr int kBandsPerWorker = 8, kMinBandRows = 32;  // apply_boolean_grain's load balance
// Below this E[U] (net above 2) a cell's disks are first checked for covering nothing new:
// at lower densities few are, and the check costs more than it saves.
constexpr double kSkipCoveredBelow = 0.01;

// Overlap area of two unit disks whose centres are u apart.
double unit_disk_overlap(double u) {
    if (u >= 2.0) return 0.0;
    return 2.0 * std::acos(0.5 * u) - 0.5 * u * std::sqrt(4.0 - u * u);
}

// Raster samples per radius that keep the lattice sum of the covariance within
// kAliasingPowerError of its integral at coverage c (the error falls about as (h/r)^3).
double samples_per_radius(double c) {
    const double exact = boolean_power_integral(c);
    if (exact <= 0) return 2.0;
    for (double k = 2.0; k < 16.0; k += 0.25)
        if (std::abs(boolean_power_lattice_sum(c, 1.0 / k) / exact - 1.0) <= BooleanGrain::kAliasingPowerError)
            return k;
    return 16.0;
}

// F(c) and the raster density at every table node: they depend on the node grid only.
struct CoverageTables {
    std::vector<double> power_integral, samples_per_radius;
};
const CoverageTables& coverage_tables() {
    static const CoverageTables tables = [] {
        CoverageTables t;
        for (int i = 0; i < kTableNodes; ++i) {
            double c = BooleanGrain::kNetCap * i / (kTableNodes - 1) * kLn10;
            t.power_integral.push_back(boolean_power_integral(c));
            t.samples_per_radius.push_back(samples_per_radius(c));
        }
        return t;
    }();
    return tables;
}

double table_at(const std::vector<double>& table, double net) {
    double pos = std::clamp(net, 0.0, BooleanGrain::kNetCap) / BooleanGrain::kNetCap * (kTableNodes - 1);
    int i = std::min(int(pos), kTableNodes - 2);
    double t = pos - i;
    return table[i] + t * (table[i + 1] - table[i]);
}

// The density a cell's grains follow: NaN counts as d_min, infinities as the float range.
double sanitized_density(float d, float d_min) {
    if (std::isnan(d)) return d_min;
    return std::clamp(double(d), -double(std::numeric_limits<float>::max()), double(std::numeric_limits<float>::max()));
}

double boolean_net(double density, float d_min) { return std::clamp(density - d_min, 0.0, BooleanGrain::kNetCap); }

// The cumulative weight of a pixel's footprint along one axis: pixel [0, p] (um) convolved
// with a Gaussian of std s truncated at +-5 s, integrated from -infinity to x.
struct FootprintCdf {
    double pitch_um, sigma_um;
    double tail, norm, anchor;  // Phi(-5), 1 - 2 Phi(-5), J's value at -5 before shifting

    FootprintCdf(double p, double s) : pitch_um(p), sigma_um(s) {
        tail = phi_cdf(-kFootprintReachSigmas);
        norm = 1.0 - 2.0 * tail;
        anchor = antiderivative(-kFootprintReachSigmas);
    }
    static double phi_cdf(double t) { return 0.5 * std::erfc(-t / std::sqrt(2.0)); }
    static double antiderivative(double t) { return t * phi_cdf(t) + std::exp(-0.5 * t * t) / std::sqrt(2.0 * M_PI); }
    // J(t) = integral from -5 to t of the truncated Gaussian's CDF.
    double integrated_cdf(double t) const {
        const double r = kFootprintReachSigmas;
        if (t <= -r) return 0.0;
        if (t >= r) return integrated_cdf_inside(r) + (t - r);
        return integrated_cdf_inside(t);
    }
    double integrated_cdf_inside(double t) const {
        return (antiderivative(t) - anchor - tail * (t + kFootprintReachSigmas)) / norm;
    }
    double operator()(double x) const {
        if (sigma_um <= 0) return std::clamp(x / pitch_um, 0.0, 1.0);
        return sigma_um / pitch_um * (integrated_cdf(x / sigma_um) - integrated_cdf((x - pitch_um) / sigma_um));
    }
};

// max(0, ceil(v)) and floor(v), branch-free (the comparisons are unpredictable): the offset
// makes the truncation a floor for |v| below it (v is within m + 2 r samples).
constexpr double kFloorOffset = 1 << 20;
constexpr double kRoundingMargin = 1e-6;  // samples; sqrt(r^2) may exceed r by an ulp
int first_index_at_or_above(double v) { return std::max(0, int(kFloorOffset) - int(kFloorOffset - v)); }
int last_index_at_or_below(double v) { return int(v + kFloorOffset) - int(kFloorOffset); }

// Bits i0..i1 (inclusive) of a row of the raster, i0 <= i1.
struct RowSpan {
    int w0, w1;            // first and last word
    uint64_t first, last;  // their masks
    RowSpan(int i0, int i1) : w0(i0 >> 6), w1(i1 >> 6), first(~0ull << (i0 & 63)), last(~0ull >> (63 - (i1 & 63))) {
        if (w0 == w1) first &= last;
    }
};

constexpr int kMaxLanes = simd::kAvx512Doubles;  // the kernels' widest
template <int lanes>
struct UnsignedLanes {  // as many uint64 lanes as simd::Lanes<lanes>::L has int64
    typedef uint64_t U __attribute__((vector_size(8 * lanes)));
};

// The OR of v's lanes: the halves ORed, down to one lane (not lane by lane, which GCC does
// by extracting each).
template <int lanes>
__attribute__((always_inline)) inline uint64_t or_lanes(const typename UnsignedLanes<lanes>::U& v) {
    if constexpr (lanes == 1) {
        return v[0];
    } else {
        typename UnsignedLanes<lanes / 2>::U low, high;
        std::memcpy(&low, &v, sizeof low);
        std::memcpy(&high, reinterpret_cast<const char*>(&v) + sizeof low, sizeof high);
        return or_lanes<lanes / 2>(low | high);
    }
}

// A cell's raster: one bit per sample, 64 samples of a row a word, word w of row j at
// [w m + j], so that the rows a disk spans are neighbours in memory; then padding, which a
// disk's last rows may read and write back unchanged.
constexpr int kRasterPaddingWords = kMaxLanes;
void clear_raster(std::vector<uint64_t>& raster, int m) {
    raster.assign(size_t(m) * size_t((m + 63) / 64) + kRasterPaddingWords, 0);
}

// Sets the bits of the samples ((i + 0.5) h, (j + 0.5) h), i in [0, m) and j in [row0, row1],
// that disks of `radius_um` cover, their centres (x_um, y_um) offset by (ox, oy) um from the
// raster's corner. A disk's rows `lanes` at a time: each lane's span from its own square root, then
// its bits in each of the disk's bounding words, ORed into `lanes` neighbouring words at
// once. The raster is a union, so with skip_covered a disk whose bounding columns are set
// in every row it spans is skipped (in a print's blacks, about half of them).
struct RasterizeDisks {
    // Disks are checked a batch at a time and the batch's uncovered ones then set, so that
    // the check's outcome, which is hard to predict, steers no branch. (A disk covered only
    // by others of its batch is set: the same bits.)
    static constexpr int kDisksPerBatch = 64;
    struct PendingDisk {
        double gx, gy;  // centre, in samples from sample (0, 0)
        int b0, b1;     // bounding columns
        int j0, j1;     // rows
    };
    // mask = all ones in the lanes k <= n, zero beyond (lane_index holds k).
    template <typename L>
    __attribute__((always_inline)) static void lanes_up_to(int n, const L& lane_index, L& mask) {
        mask = ~((int64_t(n) - lane_index) >> 63);
    }
    // Whether the box's bits are set in each row j0..j1, `lanes` rows a load, no branch a row.
    template <typename L, typename U>
    __attribute__((always_inline)) static bool all_set(const RowSpan& box, const uint64_t* raster, int j0, int j1, int m,
                                                       const L& lane_index) {
        constexpr int lanes = sizeof(L) / sizeof(int64_t);
        U missing{};
        for (int w = box.w0; w <= box.w1; ++w) {
            const uint64_t mask = w == box.w0 ? box.first : w == box.w1 ? box.last : ~0ull;
            for (int j = j0; j <= j1; j += lanes) {
                U words;
                L rows;
                simd::load(words, raster + size_t(w) * m + j);
                lanes_up_to(j1 - j, lane_index, rows);
                missing |= ~words & mask & (U)rows;
            }
        }
        return or_lanes<lanes>(missing) == 0;
    }
    template <int lanes>
    __attribute__((always_inline)) static void run(const float* x_um, const float* y_um, size_t count, double ox,
                                                   double oy, double inv_h, double radius_um, int m, int row0,
                                                   int row1, uint64_t* raster, bool skip_covered) {
        static_assert(lanes <= kMaxLanes, "a disk's last row group stays within the padding");
        using L = typename simd::Lanes<lanes>::L;
        using U = typename UnsignedLanes<lanes>::U;
        const double r = radius_um * inv_h, r2 = r * r;
        if (!skip_covered) {
            PendingDisk disk;
            for (size_t k = 0; k < count; ++k)
                if (place(x_um[k], y_um[k], ox, oy, inv_h, r, m, row0, row1, disk)) set_disk<lanes>(raster, m, disk, r2);
            return;
        }
        L lane_index;
        for (int k = 0; k < lanes; ++k) lane_index[k] = k;
        PendingDisk pending[kDisksPerBatch];
        for (size_t k0 = 0; k0 < count; k0 += kDisksPerBatch) {
            // The batch's disks that reach the raster and cover something not set before the
            // batch, kept without a branch on the check.
            int kept = 0;
            for (size_t k = k0; k < std::min(count, k0 + kDisksPerBatch); ++k) {
                PendingDisk& disk = pending[kept];
                kept += place(x_um[k], y_um[k], ox, oy, inv_h, r, m, row0, row1, disk) &&
                        !all_set<L, U>(RowSpan(disk.b0, disk.b1), raster, disk.j0, disk.j1, m, lane_index);
            }
            for (int d = 0; d < kept; ++d) set_disk<lanes>(raster, m, pending[d], r2);
        }
    }
    // The disk of radius r (samples) centred at (x_um, y_um) + (ox, oy): its centre in samples,
    // its rows within row0..row1 and its bounding columns; false where it sets no sample there.
    __attribute__((always_inline)) static bool place(float x_um, float y_um, double ox, double oy, double inv_h,
                                                     double r, int m, int row0, int row1, PendingDisk& disk) {
        // In sample units, sample (i, j) at (i + 0.5, j + 0.5): shifted by 0.5 to (i, j).
        const double gx = (ox + x_um) * inv_h - 0.5, gy = (oy + y_um) * inv_h - 0.5, extent = m;
        if (gx + r < -0.5 || gx - r > extent || gy + r < -0.5 || gy - r > extent) return false;
        disk.gx = gx, disk.gy = gy;
        disk.j0 = std::max(row0, first_index_at_or_above(gy - r));
        disk.j1 = std::min(row1, last_index_at_or_below(gy + r));
        // The bounding columns, widened by a rounding margin so that they hold every sample a
        // row of the disk sets.
        disk.b0 = first_index_at_or_above(gx - r - kRoundingMargin);
        disk.b1 = std::min(m - 1, last_index_at_or_below(gx + r + kRoundingMargin));
        return disk.b0 <= disk.b1 && disk.j0 <= disk.j1;
    }
    template <int lanes>
    __attribute__((always_inline)) static void set_disk(uint64_t* raster, int m, const PendingDisk& disk, double r2) {
        const RowSpan box(disk.b0, disk.b1);
        for (int j = disk.j0; j <= disk.j1; j += lanes) set_rows<lanes>(raster, m, box, j, disk.j1, disk.gx, disk.gy, r2);
    }
    // Sets the disk's rows j..min(j1, j + lanes - 1).
    template <int lanes>
    __attribute__((always_inline)) static void set_rows(uint64_t* raster, int m, const RowSpan& box, int j, int j1,
                                                        double gx, double gy, double r2) {
        using D = typename simd::Lanes<lanes>::D;
        using L = typename simd::Lanes<lanes>::L;
        using U = typename UnsignedLanes<lanes>::U;
        D lane_row;
        L lane_index;
        for (int k = 0; k < lanes; ++k) lane_row[k] = k, lane_index[k] = k;
        const D dy = (lane_row + double(j)) - gy, half2 = r2 - dy * dy;
        // Masks by sign bits, not comparisons (which GCC makes scalar in the kernels): the
        // lanes whose row lies within the disk's (half2 is never -0).
        L half2_bits;
        std::memcpy(&half2_bits, &half2, sizeof half2);
        L inside;
        lanes_up_to(j1 - j, lane_index, inside);
        inside &= ~(half2_bits >> 63);
        half2_bits &= inside;
        D half2_inside, half;
        std::memcpy(&half2_inside, &half2_bits, sizeof half2);
        simd::sqrt_lanes(half2_inside, half);
        // The row's span i0..i1 as first_index_at_or_above and last_index_at_or_below.
        L low, high;
        simd::truncate_lanes(kFloorOffset - (gx - half), low);
        simd::truncate_lanes((gx + half) + kFloorOffset, high);
        const L i0 = int64_t(kFloorOffset) - low, i1 = high - int64_t(kFloorOffset);
        for (int w = box.w0; w <= box.w1; ++w) {
            // The span's bits within word w, a to b (max(i0, first) and min(i1, last) from
            // it), none where b < a.
            const int64_t first_bit = 64 * w, last_bit = std::min(64 * w + 63, m - 1);
            const L from_first = i0 - first_bit, past_last = i1 - last_bit;
            const L a = from_first & ~(from_first >> 63), b = last_bit - first_bit + (past_last & (past_last >> 63));
            const L set = inside & ~((b - a) >> 63);
            const U ones = ~U{};
            const U bits = (ones << (U)(a & set)) & (ones >> (U)((63 - b) & set)) & (U)set;
            uint64_t* words = raster + size_t(w) * m + j;
            U old;
            simd::load(old, words);
            simd::store(words, old | bits);
        }
    }
};

// The centres of a cell's disks, uniform at 16-bit resolution: Philox's draw b at counter
// (cx, cy, b, tag) gives disks 4 b to 4 b + 3 from its four words, x in each word's low 16
// bits and y in its high 16, as x = c (bits + 0.5) / 65536 um. `lanes` draws at a time, so
// the arrays hold whole multiples of 4 lanes.
struct DrawCentres {
    template <int lanes>
    __attribute__((always_inline)) static void run(uint32_t cx, uint32_t cy, uint32_t tag, uint32_t key0,
                                                   uint32_t key1, uint32_t draws, double cell_um, float* x_um,
                                                   float* y_um) {
        using U = typename UnsignedLanes<lanes>::U;
        using I = typename simd::Lanes<lanes>::I;
        using D = typename simd::Lanes<lanes>::D;
        using F = typename simd::Lanes<lanes>::F;
        U lane_index;
        for (int k = 0; k < lanes; ++k) lane_index[k] = uint64_t(k);
        for (uint32_t b = 0; b < draws; b += lanes) {
            U word[4] = {};  // the counter (cx, cy, b + lane, tag); zeroed first, or GCC 12 warns
            word[0] += cx, word[1] += cy, word[2] = lane_index + b, word[3] += tag;
            philox4x32_10_rounds(word, key0, key1);
            float x[4][lanes], y[4][lanes];
            for (int k = 0; k < 4; ++k) {
                const D low = __builtin_convertvector(__builtin_convertvector(word[k] & 0xffffu, I), D),
                        high = __builtin_convertvector(__builtin_convertvector(word[k] >> 16, I), D);
                simd::store(x[k], __builtin_convertvector(cell_um * (low + 0.5) / 65536.0, F));
                simd::store(y[k], __builtin_convertvector(cell_um * (high + 0.5) / 65536.0, F));
            }
            for (int l = 0; l < lanes; ++l)
                for (int k = 0; k < 4; ++k) {
                    x_um[4 * (b + l) + k] = x[k][l];
                    y_um[4 * (b + l) + k] = y[k][l];
                }
        }
    }
};

struct CellGrains {
    double uncovered = 1;  // E[U] = 10^-net at the cell's density
    double radius_um = 0;
    double samples_per_um = 0;
    std::vector<float> x_um, y_um;  // centres from the cell's corner
    size_t border = 0;              // the first `border` disks may reach beyond the cell
};

class BandRenderer {
public:
    BandRenderer(const Plane& input, const BooleanGrain& g) : in_(input), g_(g), cdf_(g.pixel_pitch_um, g.grain_size_um) {
        Philox4x32 derived = philox4x32_10({uint32_t(g.key.frame), g.key.stream, 0x426f6f6cu, 0u}, uint32_t(g.key.seed),
                                           uint32_t(g.key.seed >> 32));
        key0_ = derived[0];
        key1_ = derived[1];
        position_tag_ = derived[2];
        count_tag_ = derived[3];
        reach_px_ = int(std::ceil(g.footprint_reach_um / g.pixel_pitch_um));
    }

    // Transmittance of pixels [in.x0, in.x1) x [y0, y1), row-major: each pixel's own mean,
    // 10^-net of its density, times the grain's relative fluctuation over its footprint, the
    // footprint's integral of U over its expectation. (The footprint reaches into the
    // neighbouring pixels, whose disks follow their own densities: its integral alone would be
    // the image blurred by the footprint's Gaussian, which the other tiers' grain does not do,
    // and which the MTF stage already accounts for. A ratio, not a difference, so that a dark
    // pixel beside a light one keeps a positive transmittance.)
    std::vector<double> render(int y0, int y1) {
        const Window& w = in_.window;
        band_ = Window{w.x0, y0, w.x1, y1};
        transmittance_.assign(size_t(band_.pixel_count()), 0.0);
        expected_.assign(size_t(band_.pixel_count()), 0.0);
        const double c = g_.cell_um, p = g_.pixel_pitch_um, reach = g_.footprint_reach_um;
        const int cx0 = int(std::floor((w.x0 * p - reach) / c)), cx1 = int(std::ceil((w.x1 * p + reach) / c));
        const int cy0 = int(std::floor((y0 * p - reach) / c)), cy1 = int(std::ceil((y1 * p + reach) / c));
        // Strips of cells aligned to absolute coordinates keep the grains held in memory
        // small; within a strip, rows top to bottom. A pixel's cells are thus always summed
        // in (strip, row, column) order, whatever the band.
        const int strip = std::max(1, int(96.0 / c));
        for (int s = floor_div(cx0, strip); s * strip < cx1; ++s) {
            const int sx0 = std::max(cx0, s * strip), sx1 = std::min(cx1, (s + 1) * strip);
            render_strip(sx0, sx1, cy0, cy1);
        }
        for (int y = y0; y < y1; ++y)
            for (int x = w.x0; x < w.x1; ++x) {
                const size_t i = size_t(y - y0) * w.width() + (x - w.x0);
                const double net = boolean_net(sanitized_density(in_.at(x, y), g_.d_min), g_.d_min);
                transmittance_[i] *= std::exp(-kLn10 * net) / expected_[i];
            }
        return std::move(transmittance_);
    }

private:
    const Plane& in_;
    const BooleanGrain& g_;
    FootprintCdf cdf_;
    uint32_t key0_ = 0, key1_ = 0, position_tag_ = 0, count_tag_ = 0;
    Philox4x32 bits_{};
    int reach_px_ = 0;
    Window band_;
    std::vector<double> transmittance_;
    std::vector<double> expected_;  // per pixel, E of its footprint's integral of U: sum of weight x uncovered
    // Grains of (2 reach + 1) cell rows, columns [grain_x0_, grain_x0_ + width), by row mod.
    std::vector<std::vector<CellGrains>> ring_;
    int grain_x0_ = 0;
    std::vector<uint64_t> covered_;  // the cell's raster (clear_raster)
    int words_ = 0;
    std::vector<double> contribution_, row_sum_;
    std::vector<int> run_ends_;  // a raster row's uncovered runs, each as its first and its end
    std::vector<float> drawn_x_, drawn_y_;
    std::map<std::pair<int, int>, std::vector<double>> cdf_tables_;  // (raster side, sub-cell)

    float density_of_cell(int cx, int cy) const {
        const Window& w = in_.window;
        int px = std::clamp(floor_div(cx, g_.cells_per_pixel), w.x0, w.x1 - 1);
        int py = std::clamp(floor_div(cy, g_.cells_per_pixel), w.y0, w.y1 - 1);
        return in_.at(px, py);
    }

    void generate(CellGrains& cell, int cx, int cy) {
        const double net = boolean_net(sanitized_density(density_of_cell(cx, cy), g_.d_min), g_.d_min);
        cell.uncovered = std::exp(-kLn10 * net);
        cell.radius_um = g_.radius_at(net);
        cell.samples_per_um = net > 0 ? table_at(g_.samples_per_um, net) : 0.0;
        const double c = g_.cell_um, r = cell.radius_um;
        const uint32_t count = poisson_count(g_.intensity_at(net) * c * c, cx, cy);
        // Uniform centres, 16-bit coordinates (c / 65536 is under 0.2 nm). Disks wholly inside
        // the cell come after those that may reach its neighbours, which only scan the first
        // `border`.
        const uint32_t draws = (count + 3) / 4;
        drawn_x_.resize(4 * size_t(draws) + 4 * kMaxLanes);
        drawn_y_.resize(drawn_x_.size());
        simd::dispatch_doubles<DrawCentres>(uint32_t(cx), uint32_t(cy), position_tag_, key0_, key1_, draws, c,
                                            drawn_x_.data(), drawn_y_.data());
        cell.x_um.resize(count);
        cell.y_um.resize(count);
        // The border disks fill the arrays from the front, the interior ones from the back
        // (the order of a cell's disks changes no bit of their union). Both places are
        // written, one kept, so that no branch follows the disk's position: between them
        // lie the places not yet kept, at least the disk's own.
        size_t border = 0, interior_from = count;
        for (uint32_t i = 0; i < count; ++i) {
            const float x = drawn_x_[i], y = drawn_y_[i];
            const bool inside = (x >= r) & (y >= r) & (x <= c - r) & (y <= c - r);
            cell.x_um[border] = cell.x_um[interior_from - 1] = x;
            cell.y_um[border] = cell.y_um[interior_from - 1] = y;
            border += !inside;
            interior_from -= inside;
        }
        cell.border = border;
    }

    // The cell's grain count, Poisson of mean `mean`: products of uniforms below 10, else
    // Hoermann's transformed rejection with squeeze (PTRS: "The transformed rejection
    // method for generating Poisson random variables", Insurance: Mathematics and
    // Economics 12, 1993), which takes about 1.15 pairs of uniforms whatever the mean.
    uint32_t poisson_count(double mean, int cx, int cy) {
        uint32_t draw = 0;
        auto uniform = [&] {
            if (draw % 4 == 0) bits_ = philox4x32_10({uint32_t(cx), uint32_t(cy), draw / 4, count_tag_}, key0_, key1_);
            return (bits_[draw++ % 4] + 0.5) * (1.0 / 4294967296.0);
        };
        if (!(mean > 0)) return 0;
        if (mean < 10) {
            const double limit = std::exp(-mean);
            uint32_t k = 0;
            for (double product = uniform(); product > limit; product *= uniform()) ++k;
            return k;
        }
        const double root = std::sqrt(mean), log_mean = std::log(mean);
        const double b = 0.931 + 2.53 * root, a = -0.059 + 0.02483 * b;
        const double inv_alpha = 1.1239 + 1.1328 / (b - 3.4), v_r = 0.9277 - 3.6224 / (b - 2);
        for (;;) {
            const double u = uniform() - 0.5, v = uniform(), us = 0.5 - std::abs(u);
            const double k = std::floor((2 * a / us + b) * u + mean + 0.43);
            if (us >= 0.07 && v <= v_r) return uint32_t(k);
            if (k < 0 || (us < 0.013 && v > us)) continue;
            if (std::log(v) + std::log(inv_alpha) - std::log(a / (us * us) + b) <= -mean + k * log_mean - log_factorial(k))
                return uint32_t(k);
        }
    }

    // ln k!: exact sums below 10, Stirling's series (error under 1e-10) above.
    static double log_factorial(double k) {
        if (k < 10) {
            double sum = 0;
            for (int i = 2; i <= int(k); ++i) sum += std::log(double(i));
            return sum;
        }
        const double x = k + 1, x2 = x * x;
        return (x - 0.5) * std::log(x) - x + 0.5 * std::log(2 * M_PI) + 1 / (12 * x) - 1 / (360 * x * x2) +
               1 / (1260 * x * x2 * x2);
    }

    CellGrains& grains(int cx, int cy) {
        const int rows = 2 * g_.grain_reach_cells + 1;
        return ring_[size_t(floor_mod(cy, rows))][size_t(cx - grain_x0_)];
    }

    void render_strip(int sx0, int sx1, int cy0, int cy1) {
        const int reach = g_.grain_reach_cells, rows = 2 * reach + 1;
        grain_x0_ = sx0 - reach;
        const int width = sx1 - sx0 + 2 * reach;
        ring_.assign(size_t(rows), std::vector<CellGrains>(size_t(width)));
        for (int cy = cy0 - reach; cy < cy0 + reach; ++cy)
            for (int i = 0; i < width; ++i) generate(grains(grain_x0_ + i, cy), grain_x0_ + i, cy);
        for (int cy = cy0; cy < cy1; ++cy) {
            for (int i = 0; i < width; ++i) generate(grains(grain_x0_ + i, cy + reach), grain_x0_ + i, cy + reach);
            for (int cx = sx0; cx < sx1; ++cx) render_cell(cx, cy);
        }
    }

    // Q(x) of each target pixel offset -reach..reach at the raster's m + 1 sample edges
    // along one axis, for a cell at sub-cell position `sub` of its pixel.
    const std::vector<double>& cdf_table(int m, int sub) {
        auto key = std::make_pair(m, sub);
        auto it = cdf_tables_.find(key);
        if (it != cdf_tables_.end()) return it->second;
        const double c = g_.cell_um, p = g_.pixel_pitch_um;
        std::vector<double> t;
        for (int k = -reach_px_; k <= reach_px_; ++k)
            for (int i = 0; i <= m; ++i) t.push_back(cdf_(sub * c + c * i / m - k * p));
        return cdf_tables_.emplace(key, std::move(t)).first->second;
    }

    void render_cell(int cx, int cy) {
        const int n = g_.cells_per_pixel, reach = g_.grain_reach_cells;
        const int px = floor_div(cx, n), py = floor_div(cy, n);
        // Target pixels this cell can reach that lie in the band.
        const int kx0 = std::max(-reach_px_, band_.x0 - px), kx1 = std::min(reach_px_, band_.x1 - 1 - px);
        const int ky0 = std::max(-reach_px_, band_.y0 - py), ky1 = std::min(reach_px_, band_.y1 - 1 - py);
        if (kx0 > kx1 || ky0 > ky1) return;

        double samples_per_um = 0;
        for (int dy = -reach; dy <= reach; ++dy)
            for (int dx = -reach; dx <= reach; ++dx)
                samples_per_um = std::max(samples_per_um, grains(cx + dx, cy + dy).samples_per_um);
        const double c = g_.cell_um;
        const int m = std::max(1, int(std::ceil(c * samples_per_um)));
        const double h = c / m;
        const std::vector<double>& qx = cdf_table(m, cx - px * n);
        const std::vector<double>& qy = cdf_table(m, cy - py * n);
        // The raster rows some pixel of the band weighs: a cell beyond the band's edge only
        // within the footprint's reach of it, and its other rows need no disks.
        int row0 = m, row1 = -1;
        for (int j = 0; j < m; ++j)
            for (int ky = ky0; ky <= ky1; ++ky) {
                const double* q = qy.data() + size_t(ky + reach_px_) * (m + 1);
                if (q[j + 1] - q[j] != 0) row0 = std::min(row0, j), row1 = j;
            }
        words_ = (m + 63) / 64;
        clear_raster(covered_, m);
        for (int dy = -reach; dy <= reach; ++dy)
            for (int dx = -reach; dx <= reach; ++dx)
                rasterize(grains(cx + dx, cy + dy), dx * c, dy * c, m, row0, row1, h, dx == 0 && dy == 0);

        const int columns = kx1 - kx0 + 1;
        contribution_.assign(size_t(ky1 - ky0 + 1) * columns, 0.0);  // [ky - ky0][kx - kx0]
        row_sum_.resize(size_t(columns));
        run_ends_.resize(size_t(m) + 1);
        for (int j = row0; j <= row1; ++j) {
            const uint64_t* row = covered_.data() + j;
            const int ends = uncovered_runs(row, m);
            // Each uncovered run adds its footprint weight, in the runs' order (a column at a
            // time, its sum in a register).
            for (int kx = kx0; kx <= kx1; ++kx) {
                const double* q = qx.data() + size_t(kx + reach_px_) * (m + 1);
                double sum = 0;
                for (int e = 0; e < ends; e += 2) sum += q[run_ends_[size_t(e + 1)]] - q[run_ends_[size_t(e)]];
                row_sum_[size_t(kx - kx0)] = sum;
            }
            for (int ky = ky0; ky <= ky1; ++ky) {
                const double* q = qy.data() + size_t(ky + reach_px_) * (m + 1);
                const double wy = q[j + 1] - q[j];
                if (wy == 0) continue;
                double* out = contribution_.data() + size_t(ky - ky0) * columns;
                for (int i = 0; i < columns; ++i) out[i] += wy * row_sum_[size_t(i)];
            }
        }
        // The footprint's weight over the whole cell (separable), at the cell's E[U]: exact
        // where the neighbouring cells share its density, and within the disks' radius of its
        // edges otherwise.
        const double uncovered = grains(cx, cy).uncovered;
        for (int ky = ky0; ky <= ky1; ++ky) {
            const double* q_y = qy.data() + size_t(ky + reach_px_) * (m + 1);
            for (int kx = kx0; kx <= kx1; ++kx) {
                const double* q_x = qx.data() + size_t(kx + reach_px_) * (m + 1);
                const size_t at = size_t(py + ky - band_.y0) * band_.width() + (px + kx - band_.x0);
                transmittance_[at] += contribution_[size_t(ky - ky0) * columns + (kx - kx0)];
                expected_[at] += (q_x[m] - q_x[0]) * (q_y[m] - q_y[0]) * uncovered;
            }
        }
    }

    // Marks the samples of the cell's raster rows row0..row1 that a cell's disks cover, its
    // centres offset by (ox, oy) um from the cell's corner; neighbours' disks are scanned only
    // if they may reach beyond their own cell.
    void rasterize(const CellGrains& cell, double ox, double oy, int m, int row0, int row1, double h, bool own) {
        const size_t count = own ? cell.x_um.size() : cell.border;
        simd::dispatch_doubles<RasterizeDisks>(cell.x_um.data(), cell.y_um.data(), count, ox, oy, 1.0 / h,
                                               cell.radius_um, m, row0, row1, covered_.data(),
                                               cell.uncovered < kSkipCoveredBelow);
    }
    // The uncovered runs [i0, i1) of a raster row (`row` its first word; its words are m
    // apart) into run_ends_, i0 and i1 in turn, and their count times 2: the samples where
    // the coverage changes, from each word's bits (samples past the row's end count as
    // covered).
    int uncovered_runs(const uint64_t* row, int m) {
        int ends = 0;
        uint64_t uncovered_before = 0;  // bit 63: the sample before the word's first
        for (int w = 0; w < words_; ++w) {
            uint64_t uncovered = ~row[size_t(w) * m];
            if (w == words_ - 1 && m % 64 != 0) uncovered &= ~0ull >> (64 - m % 64);
            for (uint64_t changes = uncovered ^ ((uncovered << 1) | (uncovered_before >> 63)); changes;
                 changes &= changes - 1)
                run_ends_[size_t(ends++)] = 64 * w + __builtin_ctzll(changes);
            uncovered_before = uncovered;
        }
        if (ends % 2 != 0) run_ends_[size_t(ends++)] = m;  // a run to the row's end
        return ends;
    }
};

}  // namespace

std::vector<uint64_t> boolean_disk_raster(const std::vector<float>& x_um, const std::vector<float>& y_um,
                                          double radius_um, double h_um, int m, bool skip_covered) {
    std::vector<uint64_t> raster;
    clear_raster(raster, m);
    simd::dispatch_doubles<RasterizeDisks>(x_um.data(), y_um.data(), std::min(x_um.size(), y_um.size()), 0.0, 0.0,
                                           1.0 / h_um, radius_um, m, 0, m - 1, raster.data(), skip_covered);
    raster.resize(raster.size() - kRasterPaddingWords);
    return raster;
}

double boolean_power_integral(double c) {
    // Midpoint rule in u over [0, 2]; g's (2 - u)^(3/2) end is smooth enough for 1e-7.
    const int steps = 4000;
    double sum = 0;
    for (int i = 0; i < steps; ++i) {
        double u = 2.0 * (i + 0.5) / steps;
        sum += 2.0 * M_PI * u * std::expm1(c * unit_disk_overlap(u) / M_PI);
    }
    return sum * 2.0 / steps;
}

double boolean_power_lattice_sum(double c, double h_over_r) {
    const int n = int(std::ceil(2.0 / h_over_r));
    double sum = 0;
    for (int j = -n; j <= n; ++j)
        for (int i = -n; i <= n; ++i) sum += std::expm1(c * unit_disk_overlap(h_over_r * std::hypot(i, j)) / M_PI);
    return sum * h_over_r * h_over_r;
}

double BooleanGrain::radius_at(double net) const { return table_at(radius_um, net); }

double BooleanGrain::intensity_at(double net) const {
    net = std::clamp(net, 0.0, kNetCap);
    if (net <= 0) return 0.0;
    double r = radius_at(net);
    return net * kLn10 / (M_PI * r * r);
}

BooleanGrain design_boolean_grain(const GrainSpec& spec, double d_min, double pixel_pitch_um, NoiseKey key) {
    BooleanGrain g;
    g.pixel_pitch_um = pixel_pitch_um;
    g.d_min = float(d_min);
    g.key = key;
    const bool valid = std::isfinite(spec.rms_granularity) && std::isfinite(spec.grain_size_um) &&
                       std::isfinite(spec.density_exponent) && std::isfinite(pixel_pitch_um) && pixel_pitch_um > 0 &&
                       spec.grain_size_um >= 0 && spec.density_exponent >= 0;
    g.noop = !valid || spec.rms_granularity <= 0 || design_grain(spec, d_min, pixel_pitch_um, key).is_noop();
    if (g.noop) return g;

    g.grain_size_um = spec.grain_size_um;
    g.footprint_reach_um = kFootprintReachSigmas * spec.grain_size_um;
    const CoverageTables& tables = coverage_tables();
    const double unit_noise_sigma48 = aperture_rms_per_unit_noise(spec.grain_size_um, kGranularityApertureUm);
    for (int i = 0; i < kTableNodes; ++i) {
        // Node 0 (no silver) takes the first node's radius: only its neighbourhood uses it.
        const int node = std::max(i, 1);
        const double net = BooleanGrain::kNetCap * node / (kTableNodes - 1);
        const double sqrt_w0 = spec.rms_granularity * std::pow(net, spec.density_exponent) / unit_noise_sigma48;
        const double r = std::clamp(kLn10 * sqrt_w0 / std::sqrt(tables.power_integral[node]),
                                    BooleanGrain::kMinRadiusUm, BooleanGrain::kMaxRadiusUm);
        g.radius_um.push_back(r);
        g.samples_per_um.push_back(tables.samples_per_radius[node] / r);
    }
    g.cells_per_pixel = std::max(1, int(std::ceil(pixel_pitch_um / kCellLimitUm)));
    g.cell_um = pixel_pitch_um / g.cells_per_pixel;
    const double max_radius = *std::max_element(g.radius_um.begin(), g.radius_um.end());
    g.grain_reach_cells = std::max(1, int(std::ceil(max_radius / g.cell_um)));
    g.halo_px = int(std::ceil((g.footprint_reach_um + (g.grain_reach_cells + 1) * g.cell_um) / pixel_pitch_um));
    return g;
}

void apply_boolean_grain(Plane& density, const BooleanGrain& g, int threads) {
    if (g.is_noop() || density.window.empty()) return;
    const Plane input = density;
    const Window w = density.window;
    // Bands claimed in turn, not one per thread: a print's blacks, where the cost lies, fill
    // some rows and not others. Each band also renders the cell rows its footprint reaches
    // beyond it (a pixel or so each side), so bands stay tens of rows tall.
    const int workers = std::min(resolve_thread_count(threads), w.height());
    const int band_rows = std::max(kMinBandRows, w.height() / (kBandsPerWorker * workers));
    const int bands = (w.height() + band_rows - 1) / band_rows;
    std::atomic<int> next_band{0};
    parallel_for(0, workers, workers, [&](int, int) {
        for (int band = next_band++; band < bands; band = next_band++) {
            const int y0 = w.y0 + band * band_rows, y1 = std::min(w.y1, y0 + band_rows);
            BandRenderer renderer(input, g);
            const std::vector<double> transmittance = renderer.render(y0, y1);
            for (int y = y0; y < y1; ++y)
                for (int x = w.x0; x < w.x1; ++x) {
                    const double d = sanitized_density(input.at(x, y), g.d_min);
                    const double t = transmittance[size_t(y - y0) * w.width() + (x - w.x0)];
                    density.at(x, y) = float(d - boolean_net(d, g.d_min) -
                                             std::log10(std::max(t, BooleanGrain::kMinTransmittance)));
                }
        }
    });
}

}  // namespace darkroom
