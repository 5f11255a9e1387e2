// A wide Gaussian on a coarser grid, for the fast tiers' smooth fields (halation's halo, the
// DIR couplers' inhibitor): block means of the image (blocks of d x d pixels aligned to the
// frame's origin, so every window and band agrees), extended past the frame by its edge
// pixels (as the exact filter reads it), a Gaussian of the width that brings a step's spread
// through the blocks, its taps and the interpolation closest to the pixels' Gaussian's, then
// bilinear interpolation back to the pixels.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <variant>
#include <vector>

#include "core/image.h"
#include "core/stages/filters.h"

namespace darkroom {

// A Gaussian of sigma_px pixels, on a grid `decimation` times coarser where that exceeds 1.
struct CoarseGaussian {
    int decimation = 1;
    std::vector<float> taps;  // pixel-integrated, unit sum, on the coarse grid
    double coarse_sigma = 0;  // their Gaussian's standard deviation, in coarse pixels
    int radius_px = 0;        // what a pixel's result reads around it
};
// The taps truncated at 4 of their sigmas (pixel_integrated_gaussian), or, with coarse_reach_sigmas
// > 0 on a coarse grid, where their last pixel reaches that many: a shorter reach is fewer taps
// and a shallower ring of rows read ahead, for the Gaussian's tail beyond it, renormalised.
CoarseGaussian design_coarse_gaussian(double sigma_px, int decimation, double coarse_reach_sigmas = 0);

// Planes' rows streamed down the rows of `out` for one thread, the blurred planes' Gaussians
// (one decimation for all) on the coarse grid. The planes' rows come from
// source(y, x_begin, x_end, rows), which writes each plane's row y (within the frame) at x in
// [x_begin, x_end) (the columns the block means read, which lie within the frame, and out's);
// they are read once each, in order, as far ahead as the Gaussian reaches (kept in a ring),
// and the coarse grid's block means, blurred rows (a SeparableStream) and their
// interpolation along x are built as they arrive. A plane without taps only passes through
// the ring.
class CoarseGaussianStream {
public:
    using Source = std::function<void(int y, int x_begin, int x_end, float* const* rows)>;
    // Or the planes' rows lent, not copied: row(y) gives each plane's row y (from column x0),
    // asked for as a Source is; each must stay as given until the stream asks for the row
    // rows_kept() past it (SeparableStream's rows_kept), and out's columns of it are the
    // caller's to change (row()'s `read`).
    struct LentRows {
        std::function<float* const*(int y)> row;
        int x0 = 0;
    };
    using Input = std::variant<Source, LentRows>;
    // How far ahead of a row the stream reads, with coarse Gaussians up to coarse_radius: the
    // ring of fine rows it keeps.
    static int rows_kept(int coarse_radius, int decimation) {
        return decimation * (coarse_radius + kCoarseRowsTogether + 1);
    }
    // A map of the blurred planes' coarse rows in place, each plane's row at rows[i] (in the
    // order of the blurred planes).
    using CoarseMap = std::function<void(float* const* rows, int width)>;
    // coarse_taps[p]: plane p's Gaussian on the coarse grid, null where it passes through.
    // means_map: applied to each row of block means before the blur (a linear map there is
    // the same, up to rounding, as on the result, on fewer values); blurred_map: to each
    // blurred coarse row before its interpolation to the pixels. geometric_floors, one a
    // blurred plane where given: its blocks' geometric means (within a factor 2^+-0.0861:
    // coarse_gaussian.cpp) in place of their means, its values below the floor (> 0) counted
    // as the floor.
    CoarseGaussianStream(const std::vector<const std::vector<float>*>& coarse_taps, int decimation, const Window& out,
                         const Window& frame, Input input, CoarseMap means_map = {}, CoarseMap blurred_map = {},
                         std::vector<float> geometric_floors = {});
    CoarseGaussianStream(const CoarseGaussianStream&) = delete;  // (its coarse streams hold `this`)
    CoarseGaussianStream& operator=(const CoarseGaussianStream&) = delete;

    // Row y of out (y increasing): each plane's row as read, on out's columns (in the ring: the
    // caller's to change until the next call), and each blurred plane's Gaussian there as
    // above[x] + t (below[x] - above[x]), its coarse rows either side interpolated along x.
    struct Row {
        std::vector<float*> read;
        std::vector<const float*> above, below;  // null for the planes that pass through
        float t = 0;
    };
    const Row& row(int y);
    // Row y of out as row() gives it, with each blurred plane's Gaussian left on the coarse
    // grid: above and below are its coarse rows either side (on the blurred window's columns),
    // for the caller to interpolate along y and then along x, fused with its use of them
    // (multiply_by_interpolated).
    const Row& coarse_row(int y);
    // product[i] = fine[i] times the coarse rows either side interpolated along y (above + t
    // (below - above), as they are read) and then along x to out's column i (i < out's width).
    void multiply_by_interpolated(const float* above, const float* below, float t, const float* fine,
                                  float* product) const;

private:
    // Two coarse rows summed at once (more would read further ahead, for a ring of fine rows
    // the deeper, and the coarse rows cost little).
    static constexpr int kCoarseRowsTogether = 2;
    // The blurred coarse rows kept where the blur wrote them: the two either side of a fine row.
    static constexpr int kCoarseRowsKept = 2;
    struct PlaneRows {
        std::vector<float> column_sums;  // none: the plane passes through
        const float* coarse[2] = {};     // blurred coarse rows j (by j's parity), in blur_'s rows
        std::vector<float> across[2];    // ... interpolated to out's columns
    };
    float* ring_row(size_t plane, int y);
    void read_to(int y);
    void block_means(int by, float* const* means);
    void keep_coarse(int j);
    void interpolate(int j);
    // Each of out's columns gets the coarse row interpolated along x (or, multiply, in's column
    // times it): `above`, or (below given) above + t (below - above).
    template <bool multiply>
    void along_x(const float* above, const float* below, float t, const float* in, float* out) const;
    const Row& read_row(int y, bool across);

    Window out_, frame_;
    Source source_;  // or:
    LentRows lent_;
    CoarseMap means_map_, blurred_map_;
    std::vector<float> geometric_floors_;
    std::vector<PlaneRows> planes_;
    std::vector<size_t> blurred_;  // the planes with a Gaussian
    int d_ = 0;
    Window means_window_, blurred_window_;
    int inside0_ = 0, inside1_ = 0;  // the frame's columns the block means read
    // Interpolation along x: out's column i (from out.x0) lies tx_[i] of the way from a coarse
    // column to the next; the runs of columns between the same two (d columns each, within).
    struct ColumnRun {
        int begin, end;  // out's columns [begin, end), from out.x0
        int block;       // the first coarse column, from blurred_window_.x0
    };
    std::vector<float> tx_;
    std::vector<ColumnRun> column_runs_;
    size_t whole_runs_[2] = {0, 0};  // the runs [first, last) of d columns each, in vectors
    std::unique_ptr<SeparableStream> blur_;
    int coarse_row_[2] = {INT32_MIN, INT32_MIN}, across_row_[2] = {INT32_MIN, INT32_MIN};
    int read_x0_ = 0, read_x1_ = 0, slots_ = 0;
    std::vector<std::vector<float, UnsetAllocator<float>>> ring_;  // per plane, the fine rows read (unset till then)
    std::vector<float*> ring_rows_;  // the planes' rows of the row being read, or (lent) of each slot
    int next_ = 0;  // the next fine row to read
    bool started_ = false;
    Row row_;
};

}  // namespace darkroom
