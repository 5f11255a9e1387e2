// The preview tier's proxy (QualityTier::proxy_scale): the frame rendered at twice the pixel
// pitch, so that grain, MTF and halation keep their size on the film, and upsampled to the
// frame's pixels. Every proxy pixel is a fixed 2x2 block of the film frame's pixels (the
// proxy grid starts at the film frame's origin), so any window, tile or thread count reads
// the same proxy pixels and gives the same output pixels as the whole frame.
#include <algorithm>
#include <chrono>
#include <limits>
#include <stdexcept>
#include <vector>

#include "core/develop.h"
#include "core/develop_rows.h"
#include "core/parallel.h"

namespace darkroom {

namespace {

constexpr int kScale = 2;  // the proxy's pixel pitch over the frame's

int floor_div(int v) { return v >= 0 ? v / kScale : -((-v + kScale - 1) / kScale); }
int ceil_div(int v) { return -floor_div(-v); }

// The proxy pixels that hold the frame's pixels of `w`.
Window proxy_cover(const Window& w) { return {floor_div(w.x0), floor_div(w.y0), ceil_div(w.x1), ceil_div(w.y1)}; }

// The frame's pixels a proxy window covers.
Window frame_cover(const Window& w) { return {w.x0 * kScale, w.y0 * kScale, w.x1 * kScale, w.y1 * kScale}; }

// Bilinear interpolation of the proxy at a frame pixel's centre: frame pixel 2X + 0.5 lies
// at proxy coordinate X - 0.25, so an even pixel takes 3/4 of proxy pixel X and 1/4 of X - 1,
// an odd one 3/4 of X and 1/4 of X + 1; at the proxy frame's edges the edge pixel repeats.
struct Taps {
    int near, far;
};
Taps taps(int x, int lo, int hi) {
    const int X = floor_div(x);
    const int other = x - X * kScale == 0 ? X - 1 : X + 1;
    return {std::clamp(X, lo, hi - 1), std::clamp(other, lo, hi - 1)};
}

// An input value as the film sees it (develop_rows.h, sanitize): NaN and -Inf no light, the
// rest held within +-kMaxInput.
inline float film_value(float v) {
    constexpr float max = float(kMaxInput);
    return v > -std::numeric_limits<float>::infinity() ? std::clamp(v, -max, max) : 0.0f;
}

void add_time(StageTimes* times, const char* stage, std::chrono::steady_clock::time_point since) {
    if (times) times->add(stage, std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count());
}

}  // namespace

FrameGeometry proxy_geometry(const FrameGeometry& frame) {
    const Window image = proxy_cover({frame.x0, frame.y0, frame.x0 + frame.width, frame.y0 + frame.height});
    FrameGeometry proxy = frame;
    proxy.x0 = image.x0, proxy.y0 = image.y0;
    proxy.width = image.width(), proxy.height = image.height();
    proxy.film_width = ceil_div(frame.film_width_px());
    return proxy;
}

Window Plan::proxy_window(const Window& output) const {
    const Window cover = proxy_cover(output);
    return Window{cover.x0 - 1, cover.y0 - 1, cover.x1 + 1, cover.y1 + 1}.intersected(proxy_->frame_);
}

void Plan::run_proxy(const ConstImageView& in, const ImageView& out, const Window& out_window, int threads,
                     StageTimes* times) const {
    const Window proxy_out = proxy_window(out_window);
    const Window proxy_in = proxy_->input_window(proxy_out);
    // Down: each proxy pixel the mean of the frame pixels of its block that the image holds,
    // as the film sees them (NaN as no light), so an image's edge block is its own pixels'.
    auto start = std::chrono::steady_clock::now();
    const int colours = colour_channel_count(in);
    Image small(proxy_in, colours);
    parallel_for(proxy_in.y0, proxy_in.y1, threads, [&](int y0, int y1) {
        for (int Y = y0; Y < y1; ++Y) {
            const Window rows = frame_cover({proxy_in.x0, Y, proxy_in.x1, Y + 1}).intersected(frame_);
            for (int X = proxy_in.x0; X < proxy_in.x1; ++X) {
                const int x0 = std::max(X * kScale, frame_.x0), x1 = std::min(X * kScale + kScale, frame_.x1);
                const float count = float((x1 - x0) * rows.height());
                float* px = small.at(X, Y);
                for (int c = 0; c < colours; ++c) {
                    float sum = 0;
                    for (int y = rows.y0; y < rows.y1; ++y)
                        for (int x = x0; x < x1; ++x) sum += film_value(in.at(x, y)[c]);
                    px[c] = sum / count;
                }
            }
        }
    });
    add_time(times, "downsample", start);

    Image result(proxy_out, 3);
    proxy_->run(small.view(), result.view(), threads, times);

    // Up: bilinear, along x then y; the input's alpha (the channel after its colour) copied
    // at the frame's pixels, as the other tiers do.
    start = std::chrono::steady_clock::now();
    const Window& pf = proxy_->frame_;
    const bool copy_alpha = colours < in.channels && out.channels >= 4;
    std::vector<Taps> columns;
    for (int x = out_window.x0; x < out_window.x1; ++x) columns.push_back(taps(x, pf.x0, pf.x1));
    parallel_for(out_window.y0, out_window.y1, threads, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const Taps ty = taps(y, pf.y0, pf.y1);
            const float* near = result.at(proxy_out.x0, ty.near);
            const float* far = result.at(proxy_out.x0, ty.far);
            float* px = out.at(out_window.x0, y);
            for (int i = 0; i < out_window.width(); ++i, px += out.pixel_stride) {
                const int n = (columns[size_t(i)].near - proxy_out.x0) * 3, f = (columns[size_t(i)].far - proxy_out.x0) * 3;
                for (int c = 0; c < 3; ++c) {
                    const float near_row = 0.75f * near[n + c] + 0.25f * near[f + c];
                    const float far_row = 0.75f * far[n + c] + 0.25f * far[f + c];
                    px[c] = 0.75f * near_row + 0.25f * far_row;
                }
                if (copy_alpha) px[3] = in.at(out_window.x0 + i, y)[colours];
            }
        }
    });
    add_time(times, "upsample", start);
}

}  // namespace darkroom
