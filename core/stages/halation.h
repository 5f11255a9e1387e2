// Halation: light that crosses the emulsion, reflects off the back of the film base and
// exposes the emulsion again around where it came in. Modelled per layer as
//   H' = H + strength * (G_radius * H),
// G a normalised Gaussian of standard deviation radius_um on the film: the added light
// is `strength` times the exposure, spread out (the base reflects, it does not absorb, so
// halation raises the exposure of bright areas' surroundings and of the areas themselves).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "core/image.h"
#include "core/stages/filters.h"
#include "core/stock.h"

namespace darkroom {

struct HalationKernel {
    double strength = 0;
    int radius = 0;           // the halo in pixels: what a pixel's result reads around it
    std::vector<float> taps;  // 1D Gaussian, integrated over each pixel, unit sum
    // Fast tiers: the Gaussian is applied on a grid this many times coarser (blocks aligned
    // to the frame's origin, so every window agrees): block means of the image extended past
    // the frame by its edge pixels (as the exact filter reads it), the Gaussian with its
    // variance reduced by the blocks' and the interpolation's (d^2/12 + d^2/6), then
    // bilinear interpolation back to the pixels. `taps` are then on the coarse grid.
    int decimation = 1;
    // Below this added fraction the stage cannot change an 8-bit or half-float result.
    static constexpr double kNoOpStrength = 1e-5;
    bool is_noop() const { return strength < kNoOpStrength; }
};

// strength is the stock's, already multiplied by the user's scale.
HalationKernel design_halation(double strength, double radius_um, double pixel_pitch_um, int decimation = 1);

// The fast tiers' halation (decimation > 1), streamed down the rows of `out` for one thread:
// row y of each plane with its halo added, y increasing. The planes' rows come from
// source(y, x_begin, x_end, rows), which writes each plane's row y (within the frame) at x in
// [x_begin, x_end) (the columns the block means read, which lie within the frame, and out's);
// they are read once each, in order, as far ahead as the halo reaches (kept in a ring), and
// the coarse grid's block means, blurred rows (a SeparableStream) and their interpolation
// along x are built as they arrive. A plane whose kernel is null passes through.
class CoarseHalationStream {
public:
    using Source = std::function<void(int y, int x_begin, int x_end, float* const* rows)>;
    CoarseHalationStream(const std::vector<const HalationKernel*>& kernels, const Window& out, const Window& frame,
                         Source source);
    CoarseHalationStream(const CoarseHalationStream&) = delete;  // (its coarse streams hold `this`)
    CoarseHalationStream& operator=(const CoarseHalationStream&) = delete;
    void row(int y, float* const* result);

private:
    struct PlaneHalo {
        float strength = 0;
        std::vector<float> column_sums;  // none: no halation
        std::vector<float> across[2];    // coarse rows j (by j's parity) interpolated to out's columns
    };
    float* ring_row(size_t plane, int y);
    void read_to(int y);
    void block_means(int by, float* const* means);
    void interpolate(int j);

    Window out_, frame_;
    Source source_;
    std::vector<PlaneHalo> planes_;
    std::vector<size_t> halated_;  // the planes with halation
    int d_ = 0;                    // their decimation
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
    std::unique_ptr<SeparableStream> blur_;
    int across_row_[2] = {INT32_MIN, INT32_MIN};
    int read_x0_ = 0, read_x1_ = 0, slots_ = 0;
    std::vector<std::vector<float, UnsetAllocator<float>>> ring_;  // per plane, the fine rows read (unset till then)
    std::vector<float*> ring_rows_;
    int next_ = 0;  // the next fine row to read
    bool started_ = false;
};

// dst = src + strength * gauss(src) on dst.window, reading src with coordinates clamped to
// `frame`; src.window must cover (dst.window grown by the radius) intersected with frame.
void apply_halation(const Plane& src, Plane& dst, const HalationKernel& kernel, const Window& frame, int threads);

}  // namespace darkroom
