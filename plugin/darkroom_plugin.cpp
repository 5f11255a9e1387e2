// Darkroom as an OpenFX image effect: the host's pixels and parameters in, core's Plan
// over them, the host's pixels out. No film physics here.
//
// File order: constants and geometry, the instance (plan and colour caches), the render
// (fetch images, read parameters, dispatch row bands on the host's threads), the other
// actions, describe, and the two exported entry points.
//
// Coordinates: OFX pixel coordinates have their origin at the bottom left; core's frames
// are top-down like the files the CLI reads. The film frame is the project's format (its
// size from its offset) at the render scale, where the host gives one and the Film frame
// parameter does not ask for the Source's own, else the Source clip's region of
// definition; core's (0, 0) is the film frame's top-left pixel and row y
// of core is OFX row (film top - 1 - y). The Source image (its region of definition) is the
// part of the film frame it covers: a CG element's bounding box, or overscan, gets the
// frame's pixel pitch and the grain those frame pixels get, as `darkroom develop` gives a
// file whose data window differs from its display window.

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <new>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "core/develop.h"
#include "core/plane_memory.h"
#include "look/render.h"
#include "look/user_error.h"
#include "plugin/ofx_abi.h"
#include "plugin/ofx_host.h"
#include "plugin/parameters.h"

namespace darkroom::ofx {

namespace {

constexpr const char* kPluginIdentifier = "org.darkroom.Darkroom";
constexpr unsigned kVersionMajor = 0, kVersionMinor = 1;
// Frames beyond this many pixels a side are refused (a render window this size is a host bug
// or a typo, and would ask for tens of gigabytes of working memory).
constexpr int kMaxFrameSidePx = 1 << 16;
constexpr long long kMaxFramePixels = 1LL << 30;
// Rows per band: enough that the scatter halo recomputed per band costs little, few enough
// that an abort is noticed quickly.
constexpr int kMinBandRows = 32;

// --- Geometry -------------------------------------------------------------------------

// A canonical rectangle in OFX pixel coordinates at a render scale.
OfxRectI frame_pixels(const OfxRectD& rod, OfxPointD scale, double pixel_aspect) {
    return {(int)std::floor(rod.x1 * scale.x / pixel_aspect), (int)std::floor(rod.y1 * scale.y),
            (int)std::ceil(rod.x2 * scale.x / pixel_aspect), (int)std::ceil(rod.y2 * scale.y)};
}

// The Source image and the film frame, in OFX pixels at the render scale (see Coordinates).
struct Placement {
    OfxRectI image, film;
};

Window to_core(const OfxRectI& r, const OfxRectI& film) {
    return {r.x1 - film.x1, film.y2 - r.y2, r.x2 - film.x1, film.y2 - r.y1};
}

OfxRectI to_ofx(const Window& w, const OfxRectI& film) {
    return {w.x0 + film.x1, film.y2 - w.y1, w.x1 + film.x1, film.y2 - w.y0};
}

std::string rect_text(const OfxRectI& r) {
    return "(" + std::to_string(r.x1) + ", " + std::to_string(r.y1) + ") - (" + std::to_string(r.x2) + ", " +
           std::to_string(r.y2) + ")";
}

// A failure the user must see, already worded.
struct RenderError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// --- The instance ---------------------------------------------------------------------

struct Instance {
    std::mutex mutex;
    // The look's renderers (its colour management and plate grain resolved) by the look's id
    // and its files' versions, and compiled plans by those and the frame; a render and its
    // region-of-interest query share one. The plans of other frames and Source regions are
    // copies of one compiled plan (Plan::in_image, Plan::for_frame): scrubbing a sequence
    // compiles once.
    std::map<std::string, std::shared_ptr<const Renderer>> renderers;
    std::map<std::string, std::shared_ptr<const Plan>> plans;
};

Instance& instance_of(OfxImageEffectHandle effect) {
    auto* inst = static_cast<Instance*>(effect_props(effect).get_pointer(kOfxPropInstanceData));
    if (!inst) throw HostError(kOfxStatErrBadHandle, "the instance has no Darkroom data");
    return *inst;
}

// The identity of a file with its modification time, so that an edited file is reloaded;
// empty for no file.
std::string file_version(const std::string& path, bool is_file = true) {
    if (!is_file || path.empty()) return "";
    std::error_code ec;
    auto t = std::filesystem::last_write_time(path, ec);
    return path + "@" + (ec ? std::string("?") : std::to_string(t.time_since_epoch().count()));
}

// What a renderer depends on: the look (its id names every setting, so a setting added to
// the table is part of it), its files' versions and the host's $OCIO.
std::string renderer_key(const NodeSettings& n) {
    const char* env = std::getenv("OCIO");
    return n.look.id() + "|" + file_version(n.look.film, n.film_from_file) + "|" +
           file_version(n.look.paper, n.paper_from_file) + "|" + file_version(n.look.grain_profile) + "|" +
           file_version(n.look.colour.config_path) + "|OCIO=" + (env ? env : "");
}

// The CPUs the host lets an effect use (its multithread suite's count; 1 without the suite).
unsigned host_cpus() {
    unsigned cpus = 1;
    if (!suites.thread || suites.thread->multiThreadNumCPUs(&cpus) != kOfxStatOK || cpus == 0) cpus = 1;
    return cpus;
}

// A look's renderer; errors name the node's parameters (UserError, worded by ofx_label).
std::shared_ptr<const Renderer> renderer_for(Instance& inst, const NodeSettings& n, const std::string& key) {
    {
        std::lock_guard<std::mutex> lock(inst.mutex);
        auto it = inst.renderers.find(key);
        if (it != inst.renderers.end()) return it->second;
    }
    auto renderer = std::make_shared<const Renderer>(n.look, ofx_label);
    std::lock_guard<std::mutex> lock(inst.mutex);
    if (inst.renderers.size() >= 8) inst.renderers.clear();  // (other looks, edited files' old versions)
    inst.renderers[key] = renderer;
    return renderer;
}

std::shared_ptr<const Plan> plan_for(Instance& inst, const Renderer& renderer, const std::string& look_key,
                                     const NodeSettings& n, const FrameGeometry& frame) {
    // One compile per film frame and look; each image window (the Source's region) and
    // frame is a copy of it.
    const std::string any_frame = look_key + "|film " + std::to_string(frame.film_width) + "x" +
                                  std::to_string(frame.film_height) + (frame.monochrome ? " grey" : ""),
                      this_frame = any_frame + "|image " + std::to_string(frame.x0) + ',' + std::to_string(frame.y0) +
                                   ',' + std::to_string(frame.width) + 'x' + std::to_string(frame.height) + "|frame " +
                                   std::to_string(n.frame);
    std::shared_ptr<const Plan> compiled;
    {
        std::lock_guard<std::mutex> lock(inst.mutex);
        auto it = inst.plans.find(this_frame);
        if (it != inst.plans.end()) return it->second;
        it = inst.plans.find(any_frame);
        if (it != inst.plans.end()) compiled = it->second;
    }
    // (its tables built on the host's CPUs, not every core: a host's budget holds)
    if (!compiled) compiled = std::make_shared<const Plan>(renderer.compile(frame, int(host_cpus())));
    auto plan = std::make_shared<const Plan>(compiled->in_image(frame).for_frame(n.frame));
    std::lock_guard<std::mutex> lock(inst.mutex);
    // Plans of other frames and settings are dropped once a few accumulate (each holds
    // kernels and tables, not images, so a handful is cheap); the compiled one is kept.
    if (inst.plans.size() >= 8) inst.plans.clear();
    inst.plans[any_frame] = compiled;
    inst.plans[this_frame] = plan;
    return plan;
}

// The look's renderer and plan for a frame.
struct Development {
    std::shared_ptr<const Renderer> renderer;
    std::shared_ptr<const Plan> plan;
};

Development development_for(Instance& inst, const NodeSettings& n, const FrameGeometry& frame) {
    const std::string key = renderer_key(n);
    Development d;
    d.renderer = renderer_for(inst, n, key);
    d.plan = plan_for(inst, *d.renderer, key, n, frame);
    return d;
}

// --- Host images ----------------------------------------------------------------------

enum class Depth { byte, ushort, float32 };

// An image fetched from a clip, released when it goes out of scope.
class HostImage {
public:
    HostImage(OfxImageClipHandle clip, OfxTime time, const char* clip_name) {
        if (suites.effect->clipGetImage(clip, time, nullptr, &handle_) != kOfxStatOK || !handle_)
            throw RenderError(std::string("the host gave no image for the ") + clip_name + " clip at time " +
                              std::to_string(time));
        try {
            describe_image(clip_name);
        } catch (...) {
            suites.effect->clipReleaseImage(handle_);
            throw;
        }
    }
    ~HostImage() {
        if (handle_) suites.effect->clipReleaseImage(handle_);
    }
    HostImage(const HostImage&) = delete;
    HostImage& operator=(const HostImage&) = delete;

    const OfxRectI& bounds() const { return bounds_; }
    int channels() const { return channels_; }
    bool premultiplied() const { return premultiplied_; }
    bool holds(int x, int y) const { return x >= bounds_.x1 && x < bounds_.x2 && y >= bounds_.y1 && y < bounds_.y2; }
    // Pixel (x, y) in OFX pixel coordinates, as floats (8- and 16-bit values scaled to 0-1).
    void read(int x, int y, float* px) const {
        const unsigned char* p = address(x, y);
        for (int c = 0; c < channels_; ++c) {
            switch (depth_) {
                case Depth::float32: px[c] = reinterpret_cast<const float*>(p)[c]; break;
                case Depth::ushort: px[c] = reinterpret_cast<const uint16_t*>(p)[c] / 65535.0f; break;
                case Depth::byte: px[c] = p[c] / 255.0f; break;
            }
        }
    }
    void write(int x, int y, const float* px) const {
        unsigned char* p = address(x, y);
        for (int c = 0; c < channels_; ++c) {
            switch (depth_) {
                case Depth::float32: reinterpret_cast<float*>(p)[c] = px[c]; break;
                case Depth::ushort:
                    reinterpret_cast<uint16_t*>(p)[c] = (uint16_t)std::lround(std::clamp(px[c], 0.0f, 1.0f) * 65535.0f);
                    break;
                case Depth::byte: p[c] = (unsigned char)std::lround(std::clamp(px[c], 0.0f, 1.0f) * 255.0f); break;
            }
        }
    }


private:
    // Reads the image's layout; throws RenderError for one the plugin cannot render.
    void describe_image(const char* clip_name) {
        Props p(handle_);
        data_ = static_cast<unsigned char*>(p.get_pointer(kOfxImagePropData));
        row_bytes_ = p.get_int(kOfxImagePropRowBytes);
        bounds_ = {p.get_int(kOfxImagePropBounds, 0), p.get_int(kOfxImagePropBounds, 1),
                   p.get_int(kOfxImagePropBounds, 2), p.get_int(kOfxImagePropBounds, 3)};
        std::string depth = p.get_string(kOfxImageEffectPropPixelDepth);
        if (depth == kOfxBitDepthFloat)
            depth_ = Depth::float32;
        else if (depth == kOfxBitDepthShort)
            depth_ = Depth::ushort;
        else if (depth == kOfxBitDepthByte)
            depth_ = Depth::byte;
        else
            throw RenderError(std::string("the ") + clip_name + " image has pixel depth '" + depth +
                              "'; Darkroom renders float, 16-bit and 8-bit images");
        std::string components = p.get_string(kOfxImageEffectPropComponents);
        if (components == kOfxImageComponentRGBA)
            channels_ = 4;
        else if (components == kOfxImageComponentRGB)
            channels_ = 3;
        else
            throw RenderError(std::string("the ") + clip_name + " image has components '" + components +
                              "'; Darkroom renders RGBA and RGB images");
        premultiplied_ = channels_ == 4 && p.get_string_or(kOfxImageEffectPropPreMultiplication, "") == kOfxImagePreMultiplied;
        if (!data_ || bounds_.x2 < bounds_.x1 || bounds_.y2 < bounds_.y1)
            throw RenderError(std::string("the host's ") + clip_name + " image has no pixels or bounds " + rect_text(bounds_));
    }

    unsigned char* address(int x, int y) const {
        size_t bytes = depth_ == Depth::float32 ? 4 : depth_ == Depth::ushort ? 2 : 1;
        return data_ + (std::ptrdiff_t)(y - bounds_.y1) * row_bytes_ + (std::ptrdiff_t)(x - bounds_.x1) * channels_ * bytes;
    }

    OfxPropertySetHandle handle_ = nullptr;
    unsigned char* data_ = nullptr;
    int row_bytes_ = 0;
    OfxRectI bounds_{};
    Depth depth_ = Depth::float32;
    int channels_ = 4;
    bool premultiplied_ = false;
};

// Working memory from the host's memory suite (so the host can account for it), or the heap.
class WorkBuffer {
public:
    WorkBuffer(OfxImageEffectHandle effect, size_t floats) {
        if (suites.memory) {
            void* p = nullptr;
            if (suites.memory->memoryAlloc(effect, floats * sizeof(float), &p) != kOfxStatOK || !p) throw std::bad_alloc();
            host_ = static_cast<float*>(p);
        } else {
            heap_.resize(floats);
        }
    }
    ~WorkBuffer() {
        if (host_) suites.memory->memoryFree(host_);
    }
    WorkBuffer(const WorkBuffer&) = delete;
    WorkBuffer& operator=(const WorkBuffer&) = delete;
    float* data() { return host_ ? host_ : heap_.data(); }

private:
    float* host_ = nullptr;
    std::vector<float> heap_;
};

// --- Render ---------------------------------------------------------------------------

// What the bands of one render share.
struct BandJob {
    OfxImageEffectHandle effect;
    const Renderer* renderer;
    const Plan* plan;
    ConstImageView input;  // in the working space, straight (Renderer::to_working)
    int premultiplied_alpha;
    int grain_frame;
    const HostImage* output;
    OfxRectI film;  // the film frame (Placement)
    std::vector<Window> bands;  // core coordinates
    std::atomic<size_t> next{0};
    std::atomic<bool> stop{false}, aborted{false};
    std::mutex error_mutex;
    std::exception_ptr error;
};

// The look's one render path over a band (look/render.h), written to the host's image.
void render_band(BandJob& job, const Window& band) {
    Image out(band, job.input.channels);
    job.renderer->render(*job.plan, job.input, out.view(), job.grain_frame, job.premultiplied_alpha, 1);
    for (int y = band.y0; y < band.y1; ++y)
        for (int x = band.x0; x < band.x1; ++x) job.output->write(x + job.film.x1, job.film.y2 - 1 - y, out.at(x, y));
}

// One of the host's threads: takes bands until none are left, the host aborts, or a band fails.
void band_worker(unsigned int, unsigned int, void* arg) {
    BandJob& job = *static_cast<BandJob*>(arg);
    for (;;) {
        if (job.stop) return;
        size_t i = job.next++;
        if (i >= job.bands.size()) return;
        if (suites.effect->abort(job.effect)) {
            job.aborted = true;
            job.stop = true;
            return;
        }
        try {
            render_band(job, job.bands[i]);
        } catch (...) {
            std::lock_guard<std::mutex> lock(job.error_mutex);
            if (!job.error) job.error = std::current_exception();
            job.stop = true;
        }
    }
}

void run_bands(BandJob& job) {
    unsigned threads = std::max(1u, std::min<unsigned>(host_cpus(), (unsigned)job.bands.size()));
    // multiThread cannot nest (the host may already be running us on one of its threads).
    if (threads == 1 || !suites.thread || suites.thread->multiThread(band_worker, threads, &job) != kOfxStatOK)
        band_worker(0, 1, &job);
}

FrameGeometry frame_geometry(const Placement& p) {
    const OfxRectI& frame = p.image;
    long long w = (long long)frame.x2 - frame.x1, h = (long long)frame.y2 - frame.y1;
    if (w <= 0 || h <= 0) throw RenderError("the Source image is empty: its region of definition is " + rect_text(frame));
    if (w > kMaxFrameSidePx || h > kMaxFrameSidePx || w * h > kMaxFramePixels)
        throw RenderError("the Source image is " + std::to_string(w) + "x" + std::to_string(h) +
                          " pixels; Darkroom renders frames up to " + std::to_string(kMaxFrameSidePx) +
                          " pixels a side and 2^30 pixels in all");
    const long long film_width = (long long)p.film.x2 - p.film.x1, film_height = (long long)p.film.y2 - p.film.y1;
    const Window image = to_core(p.image, p.film);
    return {(int)w, (int)h, false, image.x0, image.y0, (int)std::clamp(film_width, 1LL, (long long)kMaxFrameSidePx),
            (int)std::clamp(film_height, 1LL, (long long)kMaxFrameSidePx)};
}

// The Source image and the film frame at `scale`; throws when the Source is not connected.
Placement source_placement(OfxImageEffectHandle effect, OfxTime time, OfxPointD scale, const NodeSettings& settings,
                           OfxImageClipHandle* source_out) {
    OfxImageClipHandle source = clip_handle(effect, kOfxImageEffectSimpleSourceClipName);
    Props props = clip_props(source);
    if (!props.get_int_or(kOfxImageClipPropConnected, 1))
        throw RenderError("nothing is connected to the Source input");
    OfxRectD rod{};
    if (suites.effect->clipGetRegionOfDefinition(source, time, &rod) != kOfxStatOK)
        throw RenderError("the host gave no region of definition for the Source clip");
    if (source_out) *source_out = source;
    double pixel_aspect = props.get_double_or(kOfxImagePropPixelAspectRatio, 1.0);
    if (!(pixel_aspect > 0) || !std::isfinite(pixel_aspect)) pixel_aspect = 1.0;
    if (!(scale.x > 0 && scale.y > 0 && scale.x <= 1e3 && scale.y <= 1e3))
        throw RenderError("the host asked for render scale " + std::to_string(scale.x) + " x " + std::to_string(scale.y));
    Placement p;
    p.image = p.film = frame_pixels(rod, scale, pixel_aspect);
    // The project's format, where the host says (canonical coordinates; a host without it
    // leaves the film frame the image's own), unless the node takes the Source's.
    if (settings.film_frame_is_source) return p;
    Props effect_set = effect_props(effect);
    const double size_x = effect_set.get_double_or(kOfxImageEffectPropProjectSize, 0.0, 0),
                 size_y = effect_set.get_double_or(kOfxImageEffectPropProjectSize, 0.0, 1),
                 offset_x = effect_set.get_double_or(kOfxImageEffectPropProjectOffset, 0.0, 0),
                 offset_y = effect_set.get_double_or(kOfxImageEffectPropProjectOffset, 0.0, 1);
    const bool usable = size_x >= 1 && size_y >= 1 && size_x <= 1e7 && size_y <= 1e7 && std::abs(offset_x) <= 1e7 &&
                        std::abs(offset_y) <= 1e7;
    if (usable) p.film = frame_pixels({offset_x, offset_y, offset_x + size_x, offset_y + size_y}, scale, pixel_aspect);
    return p;
}

OfxPointD render_scale(const Props& args) {
    return {args.get_double_or(kOfxImageEffectPropRenderScale, 1.0, 0), args.get_double_or(kOfxImageEffectPropRenderScale, 1.0, 1)};
}

// The node's settings for a render at `scale`: a host that asks for a proxy (a render scale
// below 1, while scrubbing or dragging a slider) gets the preview tier where the node is at
// fast, the default; high and reference stay as chosen.
NodeSettings settings_at(OfxImageEffectHandle effect, OfxTime time, OfxPointD scale) {
    NodeSettings settings = read_parameters(effect, time);
    Quality& quality = settings.look.settings.quality;
    if ((scale.x < 1 || scale.y < 1) && quality == Quality::fast) quality = Quality::preview;
    return settings;
}

OfxStatus render(OfxImageEffectHandle effect, const Props& args) {
    Instance& inst = instance_of(effect);
    const OfxTime time = args.get_double(kOfxPropTime);
    const OfxPointD scale = render_scale(args);
    const OfxRectI window = {args.get_int(kOfxImageEffectPropRenderWindow, 0), args.get_int(kOfxImageEffectPropRenderWindow, 1),
                             args.get_int(kOfxImageEffectPropRenderWindow, 2), args.get_int(kOfxImageEffectPropRenderWindow, 3)};
    if (window.x2 <= window.x1 || window.y2 <= window.y1)
        throw RenderError("the host asked to render an empty window " + rect_text(window));

    NodeSettings settings = settings_at(effect, time, scale);
    OfxImageClipHandle source_clip = nullptr;
    const Placement placement = source_placement(effect, time, scale, settings, &source_clip);
    const OfxRectI& film = placement.film;
    const FrameGeometry geometry = frame_geometry(placement);

    HostImage output(clip_handle(effect, kOfxImageEffectOutputClipName), time, "Output");
    const OfxRectI& ob = output.bounds();
    if (window.x1 < ob.x1 || window.y1 < ob.y1 || window.x2 > ob.x2 || window.y2 > ob.y2)
        throw RenderError("the render window " + rect_text(window) + " is not inside the output image " + rect_text(ob));

    const Development development = development_for(inst, settings, geometry);
    const Plan& plan = *development.plan;

    // Pixels of the window outside the frame are black and transparent.
    const Window frame_core = to_core(placement.image, film);
    const Window out_core = to_core(window, film).intersected(frame_core);
    {
        const float zero[4] = {0, 0, 0, 0};
        for (int y = window.y1; y < window.y2; ++y)
            for (int x = window.x1; x < window.x2; ++x) {
                int cx = x - film.x1, cy = film.y2 - 1 - y;
                if (cx < out_core.x0 || cx >= out_core.x1 || cy < out_core.y0 || cy >= out_core.y1)
                    output.write(x, y, zero);
            }
    }
    if (out_core.empty()) {
        clear_message(effect);
        return kOfxStatOK;
    }

    // The input: the window grown by the halo, as the host has it (converted in place below).
    // The host supplies at least the region of interest asked for; anything it leaves out is black.
    HostImage source(source_clip, time, "Source");
    const Window in_core = plan.input_window(out_core);
    const int in_channels = source.channels();
    WorkBuffer in_buffer(effect, (size_t)in_core.pixel_count() * in_channels);
    ImageView in{in_buffer.data(), in_core, in_channels, in_channels, (std::ptrdiff_t)in_channels * in_core.width()};
    for (int y = in_core.y0; y < in_core.y1; ++y)
        for (int x = in_core.x0; x < in_core.x1; ++x) {
            float* px = in.at(x, y);
            int ox = x + film.x1, oy = film.y2 - 1 - y;
            if (!source.holds(ox, oy)) {
                std::fill_n(px, in_channels, 0.0f);
                continue;
            }
            source.read(ox, oy, px);
        }

    BandJob job;
    job.effect = effect;
    job.renderer = development.renderer.get();
    job.plan = &plan;
    // Straight colour in the working space, in the buffer the host's pixels were read into,
    // shared by the bands.
    job.premultiplied_alpha = source.premultiplied() ? 3 : -1;
    development.renderer->to_working(in, job.premultiplied_alpha, int(host_cpus()));
    job.input = in;
    job.grain_frame = settings.frame;
    job.output = &output;
    job.film = film;
    // Each band also develops its halo (halation's reaches ~100 px at 4K): bands of at least
    // twice the halo keep that overhead within 2x on the film's first stages, unless that
    // would leave threads without a band. Four bands per thread otherwise balance the load.
    const int threads = int(host_cpus()), height = out_core.height();
    const int per_thread = (height + threads - 1) / threads;
    int band_rows = std::max(height / (4 * threads), std::min(2 * plan.halo_px(), per_thread));
    band_rows = std::max(kMinBandRows, band_rows);
    for (int y = out_core.y0; y < out_core.y1; y += band_rows)
        job.bands.push_back({out_core.x0, y, out_core.x1, std::min(out_core.y1, y + band_rows)});
    // A reference render that will take hours says so on the node before it starts (the user
    // can abort it; one over the tier's budget is refused, an error on the node), and so does
    // a config that another stands in for (a host's ocio:// name this OCIO cannot load): the
    // message stays while the node renders that way.
    std::string warning = check_reference_render_budget(plan, out_core, "Quality ");
    if (warning.empty()) warning = development.renderer->colour().converter().config().warning;
    if (!warning.empty()) post_warning(effect, "Darkroom: " + warning);
    run_bands(job);
    if (job.error) std::rethrow_exception(job.error);
    // An aborted render is incomplete; the host discards it, so there is nothing to tell the user.
    if (job.aborted) return kOfxStatFailed;
    if (warning.empty()) clear_message(effect);
    return kOfxStatOK;
}

// --- The other actions ------------------------------------------------------------------

OfxStatus region_of_definition(OfxImageEffectHandle effect, const Props& in_args, const Props& out_args) {
    OfxImageClipHandle source = clip_handle(effect, kOfxImageEffectSimpleSourceClipName);
    if (!clip_props(source).get_int_or(kOfxImageClipPropConnected, 1)) return kOfxStatReplyDefault;
    OfxRectD rod{};
    if (suites.effect->clipGetRegionOfDefinition(source, in_args.get_double(kOfxPropTime), &rod) != kOfxStatOK)
        return kOfxStatReplyDefault;
    out_args.set_doubles(kOfxImageEffectPropRegionOfDefinition, {rod.x1, rod.y1, rod.x2, rod.y2});
    return kOfxStatOK;
}

// The Source region each output region needs: grown by the halo of scattering and halation.
OfxStatus regions_of_interest(OfxImageEffectHandle effect, const Props& in_args, const Props& out_args) {
    const OfxTime time = in_args.get_double(kOfxPropTime);
    const OfxPointD scale = render_scale(in_args);
    OfxRectD region{};
    for (int i = 0; i < 4; ++i) (&region.x1)[i] = in_args.get_double(kOfxImageEffectPropRegionOfInterest, i);
    OfxImageClipHandle source = nullptr;
    const NodeSettings settings = settings_at(effect, time, scale);
    const Placement placement = source_placement(effect, time, scale, settings, &source);
    const double pixel_aspect = clip_props(source).get_double_or(kOfxImagePropPixelAspectRatio, 1.0);
    const double sx = scale.x / (pixel_aspect > 0 ? pixel_aspect : 1.0), sy = scale.y;
    const OfxRectI region_px{(int)std::floor(std::max(region.x1 * sx, -1e9)), (int)std::floor(std::max(region.y1 * sy, -1e9)),
                             (int)std::ceil(std::min(region.x2 * sx, 1e9)), (int)std::ceil(std::min(region.y2 * sy, 1e9))};
    const FrameGeometry geometry = frame_geometry(placement);
    const Window out_core = to_core(region_px, placement.film).intersected(to_core(placement.image, placement.film));
    if (out_core.empty()) return kOfxStatReplyDefault;
    const Development development = development_for(instance_of(effect), settings, geometry);
    const OfxRectI roi = to_ofx(development.plan->input_window(out_core), placement.film);
    out_args.set_doubles((std::string(kOfxImageClipPropRoIPrefix) + kOfxImageEffectSimpleSourceClipName).c_str(),
                         {roi.x1 / sx, roi.y1 / sy, roi.x2 / sx, roi.y2 / sy});
    return kOfxStatOK;
}

// Identity: the texture output with grain, scattering and halation all off returns its input,
// and so does the whole node when the input and output colour spaces are the same.
OfxStatus is_identity(OfxImageEffectHandle effect, const Props& in_args, const Props& out_args) {
    const OfxTime time = in_args.get_double(kOfxPropTime);
    const NodeSettings n = read_parameters(effect, time);
    const DevelopSettings& s = n.look.settings;
    bool no_grain = !s.grain || (s.grain_amount[0] == 0 && s.grain_amount[1] == 0 && s.grain_amount[2] == 0);
    if (s.output != OutputMode::texture || !no_grain || s.mtf || s.halation != 0 || !n.look.grain_profile.empty() ||
        !n.look.colour.display_view.empty())
        return kOfxStatReplyDefault;
    const ocio::ColorConverter& converter = renderer_for(instance_of(effect), n, renderer_key(n))->colour().converter();
    auto canonical = [&](const std::string& space) {
        return space.empty() ? converter.working_space().color_space : converter.canonical_color_space(space);
    };
    if (canonical(n.look.colour.input_space) != canonical(n.look.colour.output_space)) return kOfxStatReplyDefault;
    out_args.set(kOfxPropName, kOfxImageEffectSimpleSourceClipName);
    out_args.set(kOfxPropTime, time);
    return kOfxStatOK;
}

OfxStatus clip_preferences(OfxImageEffectHandle effect, const Props& out_args) {
    Props source = clip_props(clip_handle(effect, kOfxImageEffectSimpleSourceClipName));
    std::string components = source.get_string_or(kOfxImageEffectPropComponents, kOfxImageComponentRGBA);
    if (components != kOfxImageComponentRGB) components = kOfxImageComponentRGBA;
    out_args.set((std::string(kOfxImageClipPropComponentsPrefix) + kOfxImageEffectOutputClipName).c_str(), components);
    out_args.set(kOfxImageEffectPropPreMultiplication,
                 source.get_string_or(kOfxImageEffectPropPreMultiplication,
                                      components == kOfxImageComponentRGB ? kOfxImageOpaque : kOfxImagePreMultiplied));
    // Grain changes with the frame unless it is off or static.
    const NodeSettings n = read_parameters(effect, 0.0);
    const DevelopSettings& s = n.look.settings;
    bool grain = (s.grain && (s.grain_amount[0] > 0 || s.grain_amount[1] > 0 || s.grain_amount[2] > 0)) ||
                 !n.look.grain_profile.empty();
    const NodeSettings n1 = read_parameters(effect, 1.0);
    out_args.set(kOfxImageEffectFrameVarying, grain && n1.frame != n.frame ? 1 : 0);
    return kOfxStatOK;
}

OfxStatus create_instance(OfxImageEffectHandle effect) {
    effect_props(effect).set(kOfxPropInstanceData, static_cast<void*>(new Instance));
    // A host that refuses values set here keeps the choices as loaded (their behaviour before
    // the saved ids); the node is still created.
    try {
        restore_stock_choices(effect);
    } catch (const std::exception&) {
    }
    return kOfxStatOK;
}

OfxStatus destroy_instance(OfxImageEffectHandle effect) {
    Props props = effect_props(effect);
    delete static_cast<Instance*>(props.get_pointer(kOfxPropInstanceData));
    props.set(kOfxPropInstanceData, static_cast<void*>(nullptr));
    return kOfxStatOK;
}

// --- Describe ---------------------------------------------------------------------------

OfxStatus describe(OfxImageEffectHandle effect) {
    Props p = effect_props(effect);
    p.set(kOfxPropLabel, "Darkroom");
    p.set(kOfxImageEffectPluginPropGrouping, "Darkroom");
    p.set(kOfxPropPluginDescription,
          "Photographic film and paper development (Geigel & Musgrave 1997, extended to colour): exposure, spectral "
          "sensitivity, MTF scattering, halation, H&D curves, grain, and the print through an enlarger.");
    p.set(kOfxImageEffectPropSupportedContexts,
          std::vector<std::string>{kOfxImageEffectContextFilter, kOfxImageEffectContextGeneral});
    p.set(kOfxImageEffectPropSupportedPixelDepths,
          std::vector<std::string>{kOfxBitDepthFloat, kOfxBitDepthShort, kOfxBitDepthByte});
    p.set(kOfxImageEffectPropSupportsMultipleClipDepths, 0);
    p.set(kOfxImageEffectPropSupportsTiles, 1);
    p.set(kOfxImageEffectPropSupportsMultiResolution, 1);
    p.set(kOfxImageEffectPropTemporalClipAccess, 0);
    p.set(kOfxImageEffectPluginPropSingleInstance, 0);
    // Renders of one instance may run at once (plans are shared under a lock); the plugin
    // splits each render over the host's threads itself.
    p.set(kOfxImageEffectPluginRenderThreadSafety, kOfxImageEffectRenderFullySafe);
    p.set(kOfxImageEffectPluginPropHostFrameThreading, 0);
    return kOfxStatOK;
}

void define_clip(OfxImageEffectHandle effect, const char* name) {
    OfxPropertySetHandle h = nullptr;
    check(suites.effect->clipDefine(effect, name, &h), (std::string("defining clip ") + name).c_str());
    Props clip(h);
    clip.set(kOfxImageEffectPropSupportedComponents,
             std::vector<std::string>{kOfxImageComponentRGBA, kOfxImageComponentRGB});
    clip.set(kOfxImageEffectPropSupportsTiles, 1);
}

OfxStatus describe_in_context(OfxImageEffectHandle effect) {
    define_clip(effect, kOfxImageEffectSimpleSourceClipName);
    define_clip(effect, kOfxImageEffectOutputClipName);
    OfxParamSetHandle params = nullptr;
    check(suites.effect->getParamSet(effect, &params), "getting the parameter set");
    define_parameters(params);
    return kOfxStatOK;
}

OfxStatus load() {
    if (!suites.host) return kOfxStatErrMissingHostFeature;
    auto fetch = [](const char* name, int version) { return suites.host->fetchSuite(suites.host->host, name, version); };
    suites.property = static_cast<const OfxPropertySuiteV1*>(fetch(kOfxPropertySuite, 1));
    suites.effect = static_cast<const OfxImageEffectSuiteV1*>(fetch(kOfxImageEffectSuite, 1));
    suites.param = static_cast<const OfxParameterSuiteV1*>(fetch(kOfxParameterSuite, 1));
    suites.memory = static_cast<const OfxMemorySuiteV1*>(fetch(kOfxMemorySuite, 1));
    suites.thread = static_cast<const OfxMultiThreadSuiteV1*>(fetch(kOfxMultiThreadSuite, 1));
    suites.message = static_cast<const OfxMessageSuiteV2*>(fetch(kOfxMessageSuite, 2));
    suites.persistent_messages = suites.message != nullptr;
    // A version-1 message suite has the first member only.
    if (!suites.message) suites.message = static_cast<const OfxMessageSuiteV2*>(fetch(kOfxMessageSuite, 1));
    if (!suites.property || !suites.effect || !suites.param) return kOfxStatErrMissingHostFeature;
    return kOfxStatOK;
}

// Actions that ask a question: when the settings cannot be used, the plugin declines to
// answer (the host then uses its default) and the render reports the problem.
bool is_query(const char* action) {
    return !std::strcmp(action, kOfxImageEffectActionGetRegionOfDefinition) ||
           !std::strcmp(action, kOfxImageEffectActionGetRegionsOfInterest) ||
           !std::strcmp(action, kOfxImageEffectActionIsIdentity) ||
           !std::strcmp(action, kOfxImageEffectActionGetClipPreferences);
}

OfxStatus dispatch(const char* action, OfxImageEffectHandle effect, OfxPropertySetHandle in_args,
                   OfxPropertySetHandle out_args) {
    if (!std::strcmp(action, kOfxActionLoad)) return load();
    if (!std::strcmp(action, kOfxActionUnload)) return kOfxStatOK;
    if (!suites.property) return kOfxStatErrMissingHostFeature;  // load failed or was not called
    if (!std::strcmp(action, kOfxActionDescribe)) return describe(effect);
    if (!std::strcmp(action, kOfxImageEffectActionDescribeInContext)) return describe_in_context(effect);
    if (!std::strcmp(action, kOfxActionCreateInstance)) return create_instance(effect);
    if (!std::strcmp(action, kOfxActionDestroyInstance)) return destroy_instance(effect);
    if (!std::strcmp(action, kOfxImageEffectActionRender)) return render(effect, Props(in_args));
    if (!std::strcmp(action, kOfxImageEffectActionGetRegionOfDefinition))
        return region_of_definition(effect, Props(in_args), Props(out_args));
    if (!std::strcmp(action, kOfxImageEffectActionGetRegionsOfInterest))
        return regions_of_interest(effect, Props(in_args), Props(out_args));
    if (!std::strcmp(action, kOfxImageEffectActionIsIdentity))
        return is_identity(effect, Props(in_args), Props(out_args));
    if (!std::strcmp(action, kOfxImageEffectActionGetClipPreferences)) return clip_preferences(effect, Props(out_args));
    if (!std::strcmp(action, kOfxActionInstanceChanged)) {
        clear_message(effect);  // the user changed something; the next render judges it afresh
        Props args(in_args);
        if (args.get_string_or(kOfxPropType, "") == kOfxTypeParameter)
            parameter_changed(effect, args.get_string_or(kOfxPropName, ""), args.get_string_or(kOfxPropChangeReason, ""),
                              args.get_double_or(kOfxPropTime, 0.0));
        return kOfxStatOK;
    }
    if (!std::strcmp(action, kOfxActionPurgeCaches)) {
        Instance& inst = instance_of(effect);
        std::lock_guard<std::mutex> lock(inst.mutex);
        inst.plans.clear();
        inst.renderers.clear();
        release_plane_memory();  // the planes' memory kept for the next render (core/plane_memory.h)
        return kOfxStatOK;
    }
    return kOfxStatReplyDefault;
}

// Nothing is thrown into the host: every failure becomes a message and a status.
OfxStatus main_entry(const char* action, const void* handle, OfxPropertySetHandle in_args,
                     OfxPropertySetHandle out_args) {
    if (!action) return kOfxStatErrUnknown;
    auto effect = static_cast<OfxImageEffectHandle>(const_cast<void*>(handle));
    const bool query = is_query(action);
    auto fail = [&](const std::string& text, OfxStatus status) {
        if (query) return kOfxStatReplyDefault;
        post_error(effect, "Darkroom: " + text);
        return status;
    };
    try {
        return dispatch(action, effect, in_args, out_args);
    } catch (const HostError& e) {
        return fail(e.what(), query ? kOfxStatReplyDefault : e.status);
    } catch (const std::bad_alloc&) {
        return fail("out of memory", kOfxStatErrMemory);
    } catch (const std::exception& e) {
        // Parameter, stock, colour and render errors: their messages name the problem.
        return fail(e.what(), kOfxStatFailed);
    } catch (...) {
        return fail("unexpected internal error", kOfxStatFailed);
    }
}

void set_host(OfxHost* host) { suites.host = host; }

OfxPlugin plugin = {kOfxImageEffectPluginApi, kOfxImageEffectPluginApiVersion, kPluginIdentifier, kVersionMajor,
                    kVersionMinor, set_host, main_entry};

}  // namespace

}  // namespace darkroom::ofx

// The only symbols the binary exports (see exports.map).
extern "C" __attribute__((visibility("default"))) OfxPlugin* OfxGetPlugin(int nth) {
    return nth == 0 ? &darkroom::ofx::plugin : nullptr;
}

extern "C" __attribute__((visibility("default"))) int OfxGetNumberOfPlugins(void) { return 1; }
