// Linear filters shared by the stages: pixel-integrated Gaussians and separable
// convolution that clamps coordinates to the frame (so a window equals that window of
// the full frame, bit for bit).
#pragma once

#include <functional>
#include <vector>

#include "core/image.h"

namespace darkroom {

// The 1D Gaussian of standard deviation sigma_px, each tap the integral over its pixel,
// truncated at 4 sigma and normalised to unit sum (one tap when sigma_px is negligible).
std::vector<float> pixel_integrated_gaussian(double sigma_px);
// The same to taps -radius ... radius.
std::vector<float> pixel_integrated_gaussian(double sigma_px, int radius);

// One row: out[x] = sum_k taps[k] in[x + k] for x in [0, width), `in` holding width +
// taps - 1 values. Summed in float in one order for every x (vectorisable, and each value
// independent of where the row starts): the order of k, except that symmetric taps sum
// taps[k] (in[x + k] + in[x + n-1-k]) for k < n/2 first, then the middle tap.
void convolve_row(const float* in, const std::vector<float>& taps, int width, float* out);
// Rows of a vertical pass (outputs 1, 2 or 4 consecutive rows at once): out[o][x] (+)= sum_k
// taps[k] rows[k + o][x] for o < outputs (rows holds taps + outputs - 1 rows), added to out
// when `add`; each value summed in convolve_row's order of the taps, however many rows are
// summed together, and the rows read from memory once for all of them. With centre_rows,
// centre * centre_rows[o][x] is then added to each sum last (as a second, one-tap pass added
// to the stored row would add it: the same value, without the pass).
void convolve_columns(const float* const* rows, const std::vector<float>& taps, int width, float* const* out,
                      int outputs, bool add, float centre = 0, const float* const* centre_rows = nullptr);

// A sum of separable filters, sum_t sign_t (taps_t in x, then taps_t in y), all of 2r + 1
// taps, plus `centre` times the pixel itself (a delta, which costs a multiply and an add where
// a term costs two passes of 2r + 1 taps). No terms and no centre: the identity.
struct SeparableFilter {
    std::vector<std::vector<float>> terms;
    std::vector<float> signs;  // +1 or -1 per term
    float centre = 0;
    // Each term's taps in y where they are not its taps in x (separable_approximation of a
    // kernel without x-y symmetry); empty: the same.
    std::vector<std::vector<float>> vertical_terms = {};
    int radius() const { return terms.empty() ? 0 : int(terms[0].size() / 2); }
    bool is_identity() const { return terms.empty() && centre == 0; }
};

// How to mix n unit white noises, each then filtered by its own kernel, so that the n fields'
// correlations at lag 0 are `field_correlation` (n x n, row-major): the lower-triangular L
// (row-major) of L L^T = the white noises' correlation. Filtering scales the correlation of
// fields a and b by their kernels' overlap (sum K_a K_b over the product of their norms,
// `kernel_overlap`, n x n), so the white noises' is the fields' over the overlap; where that
// is not positive semi-definite (a measured matrix slightly indefinite, or more correlation
// than the kernels allow) its off-diagonal terms shrink until it factors.
std::vector<double> white_noise_mixing(const std::vector<double>& field_correlation,
                                       const std::vector<double>& kernel_overlap, int n);

// Eigenvalues and orthonormal eigenvectors of a symmetric n x n matrix `a` (row-major, used
// as scratch) by cyclic Jacobi rotations; vectors[i * n + k] is component i of eigenvector k.
void symmetric_eigen(std::vector<double>& a, int n, std::vector<double>& values, std::vector<double>& vectors);

// Any kernel of (2r + 1)^2 taps (row-major: taps[(dy + r)(2r + 1) + dx + r]) as separable
// terms, from its singular value decomposition K = sum_k s_k u_k v_k^T (v_k along x, u_k along
// y), the largest first (the best approximation of each rank) until the terms left out hold at
// most `residual_energy` of the kernel's energy (the sum of its squared taps: the variance of
// unit white noise through it). 0: every term the kernel has.
SeparableFilter separable_approximation(const std::vector<double>& taps, int r, double residual_energy);

// Planes filtered as they stream down the rows, each by its own SeparableFilter, for one
// thread: output rows in increasing order, each summed from the rows its vertical pass reads
// (clamped to [row_begin, row_end)), which are filtered horizontally once each and kept in a
// ring of 2R + rows_together (R the largest radius), so that they stay in cache; up to
// `rows_together` consecutive output rows are summed at once (convolve_columns: each ring row
// is read once for all of them) where they are below rows_end, the end of the rows the stream
// is asked for. source(y, padded) writes each plane's input row y, the width + 2R values from
// R before the first output pixel. Each output value is summed in one fixed order (terms, then
// taps), so a row is the same whatever row a stream starts at and however many are summed at once.
// rows_kept > 0: each output row stays as given (in a ring of output rows) until the stream is
// asked for the row rows_kept past it, so that a caller that reads rows again later (a coarse
// grid's ring: CoarseGaussianStream) need not copy them.
class SeparableStream {
public:
    using Source = std::function<void(int y, float* const* padded)>;
    static constexpr int kMaxRowsTogether = 4;
    SeparableStream(int width, std::vector<SeparableFilter> filters, int row_begin, int row_end, int rows_end,
                    Source source, int rows_together = kMaxRowsTogether, int rows_kept = 0);
    SeparableStream(const SeparableStream&) = delete;  // (out_rows_ point into its own storage)
    SeparableStream& operator=(const SeparableStream&) = delete;
    // Output row y of each plane (width values each; y never decreases), in the stream's own
    // rows: valid until the next call (or as rows_kept says), and the caller's to change (the
    // stream reads them no more).
    float* const* row(int y);

private:
    static bool keeps_input_rows(const SeparableFilter& f);
    int padded_slots(const SeparableFilter& f) const;
    float* ring_row(size_t plane, int term, int y);
    float* padded_row(size_t plane, int y);
    int width_, radius_, row_begin_, row_end_, rows_end_, rows_together_, slots_;
    int output_slots_, identity_slots_;  // the rings of output rows and of an identity's input rows
    size_t stride_, padded_stride_;
    std::vector<SeparableFilter> filters_;
    std::vector<std::vector<std::vector<float>>> vertical_;  // per plane and term, the sign folded in
    std::vector<std::vector<float>> centre_;                  // per plane, {centre} (a one-tap vertical pass)
    // Per plane: terms x slots rows, each written before it is read (so left unset, from
    // recycled memory: core/image.h).
    std::vector<std::vector<float, UnsetAllocator<float>>> ring_;
    // Per plane, the input rows as the source writes them (width + 2R): the last
    // padded_slots() of them.
    std::vector<std::vector<float>> padded_;
    std::vector<float*> padded_rows_;
    std::vector<const float*> column_;
    // Per plane, a ring of output_slots_ output rows; out_rows_[o] points at each plane's row o
    // of the group of rows summed together (or, for the identity, its input row). Each row is
    // written before it is read (left unset, as ring_).
    std::vector<std::vector<float, UnsetAllocator<float>>> output_;
    std::vector<float*> out_rows_[kMaxRowsTogether];
    int group_y_ = 0, group_rows_ = 0;  // the group's first row and how many it holds
    Source source_;
    int next_ = 0;  // the next row to filter horizontally
    bool started_ = false;
};

// The rows of `out` filtered as above by one SeparableStream per band of rows (threads), to
// target(y), when given, else a scratch row; sink(y, filtered), when given, then receives it.
using RowSource = std::function<void(int y, float* padded)>;
using RowTarget = std::function<float*(int y)>;
using RowSink = std::function<void(int y, const float* filtered)>;
void filter_separable(const Window& out, const SeparableFilter& filter, int row_begin, int row_end, int threads,
                      const RowSource& source, const RowTarget& target, const RowSink& sink);

// A row's values beyond the frame are its edge pixels': padded holds x = first ... last - 1,
// written where inside the frame; this fills the rest from the edge values.
void hold_frame_edges(float* padded, int first, int last, const Window& frame);

// dst = separable convolution of src with taps (x then y), frame-clamped as above.
void convolve_separable(const Plane& src, Plane& dst, const std::vector<float>& taps, const Window& frame, int threads);
// dst = a sum of separable filters of src, frame-clamped as above.
void convolve_separable(const Plane& src, Plane& dst, const SeparableFilter& filter, const Window& frame, int threads);

}  // namespace darkroom
