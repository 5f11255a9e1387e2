// DIR couplers in colour development (docs/model/dir-couplers.md). Each receiver layer i of
// a colour negative develops as if its log exposure were lowered by the inhibitor around it:
//   D_i = D0_i(log10 H_i - s_i),   s_i = sum_j M_ij (G * n_j),   n_j = S_j(log10 H_j) - Dmin_j
// M the stock's matrix times the user's amount, G a Gaussian of the inhibitor's spread, S_j
// the data sheet's curve (the density a uniform field develops to, which releases the
// inhibitor) and D0_i the curve before inhibition, solved so that a neutral uniform field
// develops exactly to the sheet: D0_i(x - sum_j M_ij n_j(x)) = S_i(x).
#pragma once

#include <array>
#include <vector>

#include "core/curve.h"
#include "core/stages/coarse_gaussian.h"
#include "core/stages/tables.h"
#include "core/stock.h"

namespace darkroom {

using CouplerMatrix = std::array<std::array<double, 3>, 3>;  // [receiver][donor]

// The curves before inhibition D0_i for the sheet's curves S and matrix M: through the points
// (u_i(x), S_i(x)), u_i(x) = x - sum_j M_ij (S_j(x) - Dmin_j), at every sample x of the three
// curves (u is linear between them, so D0_i o u_i equals S_i exactly). Throws
// std::invalid_argument naming the layer where u_i falls as x rises (inhibition steeper
// than the curve: no curve before it reproduces the sheet).
std::array<Curve, 3> curves_before_inhibition(const std::array<const Curve*, 3>& sheet, const CouplerMatrix& m,
                                              const std::array<std::string, 3>& layer_names);

// The fast tiers' coarse grid for the inhibitor's spread: its spacing d at most this many of
// the Gaussian's standard deviations, so that a step's spread is within 0.030 (d / sigma)^2 <=
// 0.047 of the exact one's, and the taps' truncation within their tail; at a 4K frame's pitch
// (sigma 2.47 px) a grid of 3, where a grid of 2 cost the fast tier 5-10 % of its frame for a
// fifth less error (docs/model/dir-couplers.md).
constexpr double kCouplerGridPerSigma = 1.25;

// The develop stage's couplers, designed for a plan.
struct CouplerStage {
    std::array<float, 9> matrix{};  // M_ij at [3 i + j], the stock's times the amount
    // The inhibitor's spread; in the fast tiers on a grid up to the Gaussian's standard
    // deviation coarser (the spread net density is a smooth field: CoarseCouplerStream, which
    // evaluates the donors and the inhibition there too).
    CoarseGaussian spread;
    std::array<Curve, 3> sheet;     // the donors' curves S_j
    std::array<Curve, 3> before;    // the receivers' curves before inhibition D0_i
    std::array<double, 3> d_min{};
    std::vector<LogAxisTable> sheet_tables;  // S_j - Dmin_j tabulated, in the tiers that tabulate curves
    int radius() const { return spread.radius_px; }
    // On the coarse grid, how long CoarseCouplerStream reads each exposure row it is given
    // (CoarseGaussianStream::rows_kept; 0 without the grid).
    int rows_kept() const;
};

// The stage for a stock's couplers times `amount`, its Gaussian of diffusion_um x `spread` on
// the film at the pixel pitch, on a grid up to max_decimation times coarser. curve_table_bits
// > 0: the donors' curves tabulated (stages/tables.h).
CouplerStage design_couplers(const Stock& stock, double amount, double spread, double pixel_pitch_um,
                             int curve_table_bits, int max_decimation);

// The donors' net densities n_j of a row of layer j's exposures (lux-seconds; below 0 none).
void coupler_donor_row(const CouplerStage& c, size_t layer, const float* exposure, float* net_density, int width);

// Each layer's exposure row times 10^-s_i, s_i from the donors' spread net densities.
void inhibit_rows(const CouplerStage& c, float* const* exposure, const float* const* spread_net_density, int width);

// The couplers with their spread on the coarse grid (spread.decimation > 1), streamed down the
// rows of `out` for one thread: the layers' exposure rows from `input` (copied or lent, as
// CoarseGaussianStream reads them: within the frame, each once, in order); on the coarse
// grid, each block's mean exposure through the donors' curves, the matrix (each layer's
// exponent of 2), the Gaussian and 2^; and row(y) each layer's exposure times its factor
// interpolated from the coarse nodes, on out's columns (the stream's rows: the caller's to
// change until the next call), y increasing. Per pixel that is one interpolation and one
// product a layer; what it costs in accuracy near edges: docs/model/dir-couplers.md.
class CoarseCouplerStream {
public:
    CoarseCouplerStream(const CouplerStage& c, const Window& out, const Window& frame,
                        CoarseGaussianStream::Input input);
    float* const* row(int y);

private:
    const CouplerStage& c_;
    std::array<float, 9> m_;  // the matrix times -log2 10
    CoarseGaussianStream stream_;  // the three layers' exposures, their inhibition's factors blurred
    // The inhibited rows, apart from the exposure's ring: each ring row is written once, by the
    // scatter, and the rows multiplied stay in the cache for the develop that reads them.
    std::array<std::vector<float, UnsetAllocator<float>>, 3> rows_;
    float* out_[3];
};

}  // namespace darkroom
