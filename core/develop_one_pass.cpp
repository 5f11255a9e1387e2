// Developing with every stage a row at a time (the fast tiers, Plan::run_one_pass): each
// thread takes a band of output rows and pulls each row of each stage through the pipeline
// as the next stage needs it, so that a frame's planes never meet in memory: the input is
// read once and the output written once, and the rows between stages stay in cache (the
// rings of rows of the separable filters, the grain's noise and halation's coarse grid).
//
// The steps are the stage-by-stage run's (develop.cpp) on the same values, in the same order
// per pixel, so both give the same pixels bit for bit (tested); a band's first rows repeat
// the halo it shares with the band before.
#include <algorithm>
#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

#include "core/develop.h"
#include "core/develop_rows.h"
#include "core/material_stages.h"
#include "core/parallel.h"
#include "core/stages/filters.h"

namespace darkroom {

namespace {

// Per thread: the time since the last mark, added to the stage the mark names (a band's
// stages interleave row by row, nested streams inside one another); merged into StageTimes
// as the threads' mean, so that the stages add up to about the frame's time.
class RowClock {
public:
    explicit RowClock(bool on) : on_(on), last_(Clock::now()) {}
    // (stage null: the time goes to the next named stage.)
    void mark(const char* stage) {
        if (!on_ || !stage) return;
        const Clock::time_point now = Clock::now();
        times_.add(stage, std::chrono::duration<double>(now - last_).count());
        last_ = now;
    }
    void merge_into(StageTimes* times, int threads, std::mutex& mutex) const {
        if (!times) return;
        std::lock_guard<std::mutex> lock(mutex);
        for (const auto& [stage, seconds] : times_.seconds) times->add(stage, seconds / threads);
    }

private:
    using Clock = std::chrono::steady_clock;
    bool on_;
    Clock::time_point last_;
    StageTimes times_;
};

// A material's scatter kernels as its stream's filters, their largest radius, and the stage
// they are timed as: none where no layer has one (the stream then only passes the rows through).
struct ScatterFilters {
    explicit ScatterFilters(const MaterialStages& m) {
        for (const ScatterKernel& k : m.scatter) {
            filters.push_back(k.separable_filter());
            radius = std::max(radius, filters.back().radius());
            if (!k.is_identity()) stage = "scatter";
        }
    }
    std::vector<SeparableFilter> filters;
    int radius = 0;
    const char* stage = nullptr;
};

// Every layer's scatter kernel can stream: separable, or none.
bool separable_scatter(const MaterialStages& m) {
    for (const ScatterKernel& k : m.scatter)
        if (!k.is_identity() && k.separable.empty()) return false;
    return true;
}

// Develops the layers' rows (exposures to densities, in place or into other rows), with grain
// where a layer has it.
class LayerDevelop {
public:
    LayerDevelop(const MaterialStages& m, const Window& w) : m_(m) {
        std::vector<const GrainModel*> grains;
        for (const auto& g : m.grain)
            if (g) grains.push_back(&*g);
        if (!grains.empty()) noise_stream_ = std::make_unique<GrainNoiseStream>(grains, w);
    }
    void row(int y, const float* const* exposure, float* const* density, int width, RowClock& clock) {
        const float* const* noise = noise_stream_ ? noise_stream_->row(y) : nullptr;
        size_t g = 0;
        for (size_t l = 0; l < m_.curve_tables.size(); ++l) {
            if (m_.grain[l])
                develop_row_with_grain(m_.curve_tables[l], *m_.grain[l], noise[g++], width, exposure[l], density[l]);
            else
                m_.curve_tables[l].apply_row(exposure[l], density[l], width);
        }
        clock.mark(kDevelopAndGrainStage);
    }

private:
    const MaterialStages& m_;
    std::unique_ptr<GrainNoiseStream> noise_stream_;
};

// The DIR couplers (core/stages/couplers.h) on the scattered exposure as it streams down the
// rows: the donors' net densities of each row the scatter gives (on `film` grown by the
// inhibitor's reach, `scattered`), spread by their own stream (on the coarse grid where the
// stage has one: CoarseCouplerStream), and each row's exposure kept in a ring until its
// inhibition is known. The same steps as develop.cpp's inhibited_exposure.
class CouplerStream {
public:
    using ScatteredRow = std::function<float* const*(int y)>;  // row y of the three layers on `scattered`
    CouplerStream(const CouplerStage& c, const Window& film, const Window& scattered, const Window& frame, int rows_end,
                  ScatteredRow scattered_row)
        : c_(c), offset_(film.x0 - scattered.x0), width_(film.width()), stride_(scattered.width()) {
        if (c.spread.decimation > 1) {  // (the scatter's rows lent: it keeps c.rows_kept() of them)
            coarse_ = std::make_unique<CoarseCouplerStream>(
                c, film, frame, CoarseGaussianStream::LentRows{std::move(scattered_row), scattered.x0});
            return;
        }
        slots_ = 2 * c.radius() + 2 * SeparableStream::kMaxRowsTogether + 2;
        ring_.assign(3, std::vector<float>(size_t(slots_) * size_t(stride_)));
        spread_ = std::make_unique<SeparableStream>(
            film.width(), std::vector<SeparableFilter>(3, SeparableFilter{{c.spread.taps}, {1.0f}}), frame.y0, frame.y1,
            rows_end, [this, film, scattered, frame, scattered_row](int y, float* const* padded) {
                float* const* rows = scattered_row(y);
                const int padded_x0 = film.x0 - c_.radius(), padded_x1 = film.x1 + c_.radius();
                for (size_t l = 0; l < 3; ++l) {
                    std::copy_n(rows[l], stride_, kept(l, y));
                    coupler_donor_row(c_, l, rows[l], padded[l] + (scattered.x0 - padded_x0), stride_);
                    hold_frame_edges(padded[l], padded_x0, padded_x1, frame);
                }
            });
    }
    // Row y's inhibited exposure of each layer on `film`, in the stream's own rows (the caller's
    // to change until the next call).
    float* const* row(int y) {
        if (coarse_) return coarse_->row(y);
        const float* const* spread = spread_->row(y);
        for (size_t l = 0; l < 3; ++l) out_[l] = kept(l, y) + offset_;
        inhibit_rows(c_, out_, spread, width_);
        return out_;
    }

private:
    float* kept(size_t layer, int y) {
        return ring_[layer].data() + size_t(floor_mod(y, slots_)) * size_t(stride_);
    }
    const CouplerStage& c_;
    int offset_, width_, stride_, slots_ = 0;
    std::unique_ptr<CoarseCouplerStream> coarse_;  // or:
    std::vector<std::vector<float>> ring_;         // per layer, slots_ rows of `scattered`'s width
    std::unique_ptr<SeparableStream> spread_;
    float* out_[3];
};

// Rows of `planes` planes of a window's width.
struct Rows {
    Rows(size_t planes, int width) : storage(planes, std::vector<float>(size_t(width))) {
        for (auto& r : storage) pointers.push_back(r.data());
    }
    std::vector<std::vector<float>> storage;
    std::vector<float*> pointers;
    float* const* data() { return pointers.data(); }
};

}  // namespace

bool Plan::runs_in_one_pass() const {
    if (!structure_.one_pass || settings_.output == OutputMode::texture) return false;
    const MaterialStages& film = *film_stages_;
    if (film.curve_tables.empty() || !separable_scatter(film)) return false;  // (the tiers that tabulate curves)
    int decimation = 0;  // the film's halation on one coarse grid
    for (size_t l = 0; l < film.halation.size(); ++l) {
        if (film.boolean_grain[l]) return false;
        if (!film.halation[l]) continue;
        if (film.halation[l]->decimation <= 1 || (decimation && film.halation[l]->decimation != decimation)) return false;
        decimation = film.halation[l]->decimation;
    }
    if (!print_) return true;
    // A print through the one table (the paper's grain and halation folded into the film's or
    // left out, its MTF on the negative's densities).
    return print_table_ && separable_scatter(*paper_stages_);
}

void Plan::run_one_pass(const ConstImageView& in, const ImageView& out, const Window& out_window, int threads,
                        StageTimes* times, const ProxyBlocks* blocks_of) const {
    const MaterialStages& film = *film_stages_;
    const size_t layers = film.stock.layers.size();
    const int paper_halo = print_ ? paper_stages_->halo_px() : 0;
    const Window film_window = out_window.grown(paper_halo).intersected(frame_);  // the film's densities
    const ScatterFilters film_scatter_filters(film);
    const int film_radius = film_scatter_filters.radius;
    // The DIR couplers' inhibitor reaches this far: the scatter's output spans its columns too.
    const int coupler_radius = film.couplers ? film.couplers->radius() : 0;
    const Window scattered = film_window.grown(coupler_radius).intersected(frame_);
    // The exposure the film's scatter reads: its rows past the frame's edges are its edge pixels'.
    const int padded_x0 = scattered.x0 - film_radius, padded_x1 = scattered.x1 + film_radius;
    const FilmExposure exposure(in, film.rgb_weights, monochrome_input_, film_exposure_scale_, blocks_of);
    std::vector<const HalationKernel*> halation_kernels;  // per layer, null where it has none
    for (const auto& h : film.halation) halation_kernels.push_back(h ? &*h : nullptr);
    const bool halated = std::any_of(film.halation.begin(), film.halation.end(), [](const auto& h) { return bool(h); });

    const ScatterFilters paper_scatter_filters(*paper_stages_);  // (none when the output is no print)
    std::mutex times_mutex;
    const int bands = std::min(resolve_thread_count(threads), out_window.height());  // as parallel_for splits
    parallel_for(out_window.y0, out_window.y1, threads, [&](int band_begin, int band_end) {
        RowClock clock(times != nullptr);
        // Film: exposure and halation -> scatter -> develop and grain, on film_window's columns,
        // for the rows the band's print reads.
        const Window film_rows{film_window.x0, std::max(film_window.y0, band_begin - paper_halo), film_window.x1,
                               std::min(film_window.y1, band_end + paper_halo)};
        const Window scattered_rows{scattered.x0, std::max(frame_.y0, film_rows.y0 - coupler_radius), scattered.x1,
                                    std::min(frame_.y1, film_rows.y1 + coupler_radius)};
        const Window exposed = scattered_rows.grown(film_radius).intersected(frame_);
        std::unique_ptr<CoarseHalationStream> halation;
        if (halated)
            halation = std::make_unique<CoarseHalationStream>(
                halation_kernels, exposed, frame_, [&](int y, int x_begin, int x_end, float* const* rows) {
                    exposure.row(y, x_begin, x_end - x_begin, rows);
                    clock.mark("expose");
                });
        // (With the couplers on their coarse grid, each row kept as long as they read it.)
        const int scattered_rows_kept = film.couplers ? film.couplers->rows_kept() : 0;
        SeparableStream film_scatter(scattered.width(), film_scatter_filters.filters, frame_.y0, frame_.y1,
                                     scattered_rows.y1, [&](int y, float* const* padded) {
            clock.mark(film_scatter_filters.stage);  // (the filtering of the rows read before)
            float* inside[3];
            for (size_t l = 0; l < layers; ++l) inside[l] = padded[l] + (exposed.x0 - padded_x0);
            if (halation) {
                halation->row(y, inside);
                clock.mark("halation");
            } else {
                exposure.row(y, exposed.x0, exposed.width(), inside);
                clock.mark("expose");
            }
            for (size_t l = 0; l < layers; ++l) hold_frame_edges(padded[l], padded_x0, padded_x1, frame_);
        }, SeparableStream::kMaxRowsTogether, scattered_rows_kept);
        std::unique_ptr<CouplerStream> couplers;
        if (film.couplers)
            couplers = std::make_unique<CouplerStream>(*film.couplers, film_window, scattered, frame_, film_rows.y1,
                                                       [&](int y) {
                                                           // (the coarse grid's work on the rows before)
                                                           clock.mark("DIR couplers");
                                                           float* const* rows = film_scatter.row(y);
                                                           clock.mark(film_scatter_filters.stage);
                                                           return rows;
                                                       });
        LayerDevelop film_develop(film, film_window);
        // film_window's row y of each layer's densities, into `density`, or (null) in the scatter's
        // (or the couplers') rows, which it returns.
        auto film_density_row = [&](int y, float* const* density) {
            float* const* exposure;
            if (couplers) {
                exposure = couplers->row(y);
                clock.mark("DIR couplers");
            } else {
                exposure = film_scatter.row(y);
                clock.mark(film_scatter_filters.stage);
            }
            if (!density) density = exposure;
            film_develop.row(y, exposure, density, film_window.width(), clock);
            return density;
        };
        if (!print_) {
            Rows viewed(views_film_ ? 3 : 0, film_window.width());  // a reversal film's print
            for (int y = band_begin; y < band_end; ++y) {
                float* const* density = film_density_row(y, nullptr);
                if (views_film_) {
                    view_film_row(density, viewed.data(), film_window.width());
                    clock.mark("view");
                    write_row(viewed.data(), 3, in, out, y, out_window.x0, out_window.width());
                    clock.mark("write");
                    continue;
                }
                for (size_t l = 0; l < layers; ++l)
                    convert_row(settings_.output, scan_base_density_[l], density[l],
                                film_window.width());
                clock.mark("convert");
                write_row(density, layers, in, out, y, out_window.x0, out_window.width());
                clock.mark("write");
            }
            clock.merge_into(times, bands, times_mutex);
            return;
        }

        // The print: the negative's densities -> the paper's scatter (its MTF), on out_window's
        // columns with the paper's halo -> the print table.
        const ScatterFilters& paper = paper_scatter_filters;
        const int paper_x0 = out_window.x0 - paper.radius, paper_x1 = out_window.x1 + paper.radius;
        SeparableStream paper_scatter(out_window.width(), paper.filters, frame_.y0, frame_.y1, band_end,
                                      [&](int y, float* const* padded) {
                                          clock.mark(paper.stage);  // (the filtering of the rows read before)
                                          float* inside[3];
                                          for (int j = 0; j < 3; ++j) inside[j] = padded[j] + (film_window.x0 - paper_x0);
                                          film_density_row(y, inside);
                                          for (int j = 0; j < 3; ++j) hold_frame_edges(padded[j], paper_x0, paper_x1, frame_);
                                      });
        Rows result(3, out_window.width());
        for (int y = band_begin; y < band_end; ++y) {
            float* const* spread = paper_scatter.row(y);
            clock.mark(paper.stage);
            print_table_->apply_row(spread, result.data(), out_window.width());
            clock.mark("print table");
            write_row(result.data(), 3, in, out, y, out_window.x0, out_window.width());
            clock.mark("write");
        }
        clock.merge_into(times, bands, times_mutex);
    });
}

}  // namespace darkroom
