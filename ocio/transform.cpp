#include "ocio/transform.h"

#include <algorithm>
#include <cctype>
#include <map>
#include <mutex>
#include <stdexcept>
#include <vector>

#include "core/parallel.h"

namespace darkroom::ocio {

namespace {

// Process-wide: plugin instances and CLI stages that share a config share processors.
std::mutex cache_mutex;
std::map<std::string, ConversionPtr> conversion_cache;

std::string quoted(const std::string& s) { return "'" + s + "'"; }

// The config's spelling of `wanted` among `names` (OCIO compares names ignoring case),
// or "" if absent.
std::string find_name(const std::vector<std::string>& names, const std::string& wanted) {
    auto lower = [](std::string s) {
        for (char& c : s) c = (char)std::tolower((unsigned char)c);
        return s;
    };
    for (const std::string& name : names)
        if (lower(name) == lower(wanted)) return name;
    return "";
}

// Converts `n` grey pixels (R = G = B) through `cpu`, storing the mean of the result.
void apply_grey_row(const OCIO::CPUProcessor& cpu, float* first, int n, std::ptrdiff_t pixel_stride,
                    std::vector<float>& rgb) {
    rgb.resize((std::size_t)n * 3);
    for (int x = 0; x < n; ++x) {
        const float v = first[x * pixel_stride];
        rgb[3 * x] = rgb[3 * x + 1] = rgb[3 * x + 2] = v;
    }
    OCIO::PackedImageDesc desc(rgb.data(), n, 1, 3);
    cpu.apply(desc);
    for (int x = 0; x < n; ++x) first[x * pixel_stride] = (rgb[3 * x] + rgb[3 * x + 1] + rgb[3 * x + 2]) / 3.0f;
}

}  // namespace

// ---- Conversion ----

Conversion::Conversion(OCIO::ConstProcessorRcPtr processor, std::string description)
    : description_(std::move(description)) {
    // The processor as made holds every step; optimised losslessly, inverse pairs
    // (log then antilog, a matrix then its inverse) cancel, so a round trip is a no-op.
    if (processor && !processor->getOptimizedProcessor(OCIO::OPTIMIZATION_LOSSLESS)->isNoOp()) {
        processor_ = std::move(processor);
        cpu_ = processor_->getDefaultCPUProcessor();
    }
}

void Conversion::apply(const PixelBuffer& pixels, int threads) const {
    if (!cpu_ || !pixels.data || pixels.width <= 0 || pixels.height <= 0) return;
    if (pixels.channels <= 0) throw std::invalid_argument("darkroom::ocio: a pixel buffer needs channels");
    if (pixels.pixel_stride < pixels.channels)
        throw std::invalid_argument("darkroom::ocio: the pixel stride is smaller than the channel count");
    // Each pixel is converted on its own, so the row bands cannot change the result.
    parallel_for(0, pixels.height, threads, [&](int y0, int y1) {
        std::vector<float> grey_scratch;
        for (int y = y0; y < y1; ++y) {
            float* row = pixels.data + y * pixels.row_stride;
            if (pixels.channels < 3) {
                apply_grey_row(*cpu_, row, pixels.width, pixels.pixel_stride, grey_scratch);
                continue;
            }
            // RGB only: further channels are stepped over by the pixel stride.
            OCIO::PackedImageDesc desc(row, pixels.width, 1, 3, OCIO::BIT_DEPTH_F32, sizeof(float),
                                       pixels.pixel_stride * (std::ptrdiff_t)sizeof(float), OCIO::AutoStride);
            cpu_->apply(desc);
        }
    });
}

void Conversion::apply_rgb(float* rgb, std::size_t n_pixels) const {
    if (!cpu_ || n_pixels == 0) return;
    // OCIO takes a long width: go in slices so any count fits.
    const std::size_t slice = 1u << 20;
    for (std::size_t start = 0; start < n_pixels; start += slice) {
        const std::size_t n = std::min(slice, n_pixels - start);
        OCIO::PackedImageDesc desc(rgb + 3 * start, (long)n, 1, 3);
        cpu_->apply(desc);
    }
}

// ---- Working space ----

const std::vector<std::string>& working_space_candidate_names() {
    static const std::vector<std::string> names = {kWorkingSpaceName,         "Linear Rec.709 (sRGB)",
                                                   "lin_rec709_srgb",         "Utility - Linear - sRGB",
                                                   "Linear Rec.709",          "lin_srgb"};
    return names;
}

std::string WorkingSpaceLink::describe() const {
    if (!color_space.empty()) return "working space: " + quoted(color_space) + " (scene-linear Rec.709, D65)";
    if (!aces_interchange.empty())
        return "working space: linear Rec.709 (D65), reached through the config's aces_interchange role " +
               quoted(aces_interchange) + " with OCIO built-in transforms";
    return "working space: not found: " + problem;
}

namespace {

WorkingSpaceLink find_working_space(const ActiveConfig& active) {
    const OCIO::Config& config = *active.config;
    WorkingSpaceLink link;
    for (const std::string& name : working_space_candidate_names()) {
        OCIO::ConstColorSpaceRcPtr cs = config.getColorSpace(name.c_str());
        if (cs && !cs->isData() && cs->getReferenceSpaceType() == OCIO::REFERENCE_SPACE_SCENE) {
            link.color_space = cs->getName();
            return link;
        }
    }
    OCIO::ConstColorSpaceRcPtr aces = config.getColorSpace(OCIO::ROLE_INTERCHANGE_SCENE);
    if (aces) {
        link.aces_interchange = aces->getName();
        return link;
    }
    link.problem = active.name() + " has no linear Rec.709 colour space (looked for " +
                   join_names(working_space_candidate_names()) + ") and no '" + OCIO::ROLE_INTERCHANGE_SCENE +
                   "' role to reach one through ACES2065-1";
    return link;
}

}  // namespace

// ---- ColorConverter ----

ColorConverter::ColorConverter(ActiveConfig config) : config_(std::move(config)), link_(find_working_space(config_)) {}

void ColorConverter::require_working_space() const {
    if (!link_.problem.empty()) throw ConfigError(link_.problem);
}

std::string ColorConverter::canonical_color_space(const std::string& name) const {
    OCIO::ConstColorSpaceRcPtr cs = config_.config->getColorSpace(name.c_str());
    if (!cs)
        throw UnknownNameError("unknown colour space " + quoted(name) + " in " + config_.name() +
                               "; it defines (aliases and roles also work): " +
                               join_names(color_space_names(*config_.config)));
    return cs->getName();
}

std::string ColorConverter::encoding(const std::string& color_space) const {
    OCIO::ConstColorSpaceRcPtr cs = config_.config->getColorSpace(canonical_color_space(color_space).c_str());
    if (cs->isData()) return "data";
    return cs->getEncoding();
}

std::pair<std::string, std::string> ColorConverter::resolve_display_view(const std::string& display,
                                                                         const std::string& view) const {
    const OCIO::Config& config = *config_.config;
    const std::vector<std::string> displays = display_names(config);
    if (displays.empty())
        throw ConfigError(config_.name() + " defines no displays (so no default display): name an output colour space "
                                           "instead, or use a config with displays");
    const std::string wanted_display = display.empty() ? std::string(config.getDefaultDisplay()) : display;
    const std::string chosen_display = find_name(displays, wanted_display);
    if (chosen_display.empty())
        throw UnknownNameError("unknown display " + quoted(wanted_display) + " in " + config_.name() +
                               "; it defines: " + join_names(displays));
    const std::vector<std::string> views = view_names(config, chosen_display);
    if (views.empty())
        throw ConfigError(config_.name() + ": display " + quoted(chosen_display) + " has no views");
    const std::string wanted_view = view.empty() ? std::string(config.getDefaultView(chosen_display.c_str())) : view;
    const std::string chosen_view = find_name(views, wanted_view);
    if (chosen_view.empty())
        throw UnknownNameError("unknown view " + quoted(wanted_view) + " of display " + quoted(chosen_display) +
                               " in " + config_.name() + "; it has: " + join_names(views));
    return {chosen_display, chosen_view};
}

std::string ColorConverter::display_view_color_space(const std::string& display, const std::string& view) const {
    const auto [chosen_display, chosen_view] = resolve_display_view(display, view);
    const std::string name = config_.config->getDisplayViewColorSpaceName(chosen_display.c_str(), chosen_view.c_str());
    // OCIO's token for a shared view whose colour space is named like the display.
    return name == "<USE_DISPLAY_NAME>" ? chosen_display : name;
}

ConversionPtr ColorConverter::cached(const std::string& key, const std::string& description,
                                     const std::function<OCIO::ConstTransformRcPtr()>& make) const {
    const std::string full_key = config_.cache_id + '\n' + key;
    std::lock_guard<std::mutex> lock(cache_mutex);
    auto it = conversion_cache.find(full_key);
    if (it != conversion_cache.end()) return it->second;
    OCIO::ConstProcessorRcPtr processor;
    try {
        const OCIO::ConstTransformRcPtr transform = make();
        if (transform) processor = config_.config->getProcessor(transform);
    } catch (const OCIO::Exception& e) {
        throw ConfigError(config_.name() + " cannot convert " + description + ": " + e.what());
    }
    ConversionPtr conversion = std::make_shared<const Conversion>(processor, description);
    conversion_cache.emplace(full_key, conversion);
    return conversion;
}

bool ColorConverter::is_data(const std::string& color_space) const {
    OCIO::ConstColorSpaceRcPtr cs = config_.config->getColorSpace(color_space.c_str());
    return cs && cs->isData();
}

std::string ColorConverter::working_space_label() const {
    return link_.color_space.empty() ? "linear Rec.709" : link_.color_space;
}

OCIO::ConstTransformRcPtr ColorConverter::from_result(
    ResultEncoding source, const std::function<OCIO::TransformRcPtr(const std::string&)>& then) const {
    OCIO::GroupTransformRcPtr g = OCIO::GroupTransform::Create();
    if (source == ResultEncoding::cineon_log) g->appendTransform(cineon_log_to_lin_rec709());
    if (link_.color_space.empty()) {
        g->appendTransform(lin_rec709_to_aces2065_1());
        g->appendTransform(then(link_.aces_interchange));
    } else {
        g->appendTransform(then(link_.color_space));
    }
    return g;
}

namespace {

OCIO::TransformRcPtr color_space_transform(const std::string& src, const std::string& dst) {
    OCIO::ColorSpaceTransformRcPtr t = OCIO::ColorSpaceTransform::Create();
    t->setSrc(src.c_str());
    t->setDst(dst.c_str());
    return t;
}

OCIO::TransformRcPtr display_view_transform(const std::string& src, const std::string& display,
                                            const std::string& view) {
    OCIO::DisplayViewTransformRcPtr t = OCIO::DisplayViewTransform::Create();
    t->setSrc(src.c_str());
    t->setDisplay(display.c_str());
    t->setView(view.c_str());
    return t;
}

}  // namespace

namespace {

const char* result_key(ResultEncoding source) {
    return source == ResultEncoding::cineon_log ? "cineon_log" : "working";
}

std::string result_label(ResultEncoding source, const std::string& working) {
    return source == ResultEncoding::cineon_log ? "'Cineon Log' (the scan)" : "'" + working + "'";
}

}  // namespace

ConversionPtr ColorConverter::to_working(const std::string& color_space) const {
    const std::string src = canonical_color_space(color_space);
    require_working_space();
    return cached("to_working\n" + src, quoted(src) + " -> " + quoted(working_space_label()),
                  [&]() -> OCIO::ConstTransformRcPtr {
                      if (!link_.color_space.empty()) return color_space_transform(src, link_.color_space);
                      OCIO::GroupTransformRcPtr g = OCIO::GroupTransform::Create();
                      g->appendTransform(color_space_transform(src, link_.aces_interchange));
                      OCIO::GroupTransformRcPtr aces_to_working = lin_rec709_to_aces2065_1();
                      aces_to_working->setDirection(OCIO::TRANSFORM_DIR_INVERSE);
                      g->appendTransform(aces_to_working);
                      return g;
                  });
}

ConversionPtr ColorConverter::from_working(const std::string& color_space, ResultEncoding source) const {
    const std::string dst = canonical_color_space(color_space);
    require_working_space();
    return cached(std::string("from_") + result_key(source) + "\n" + dst,
                  result_label(source, working_space_label()) + " -> " + quoted(dst),
                  [&]() -> OCIO::ConstTransformRcPtr {
                      // Data spaces take pixels as they are (OCIO's rule), the scan included.
                      if (is_data(dst)) return nullptr;
                      return from_result(source, [&](const std::string& src) { return color_space_transform(src, dst); });
                  });
}

ConversionPtr ColorConverter::to_display(const std::string& display, const std::string& view,
                                         ResultEncoding source) const {
    const std::pair<std::string, std::string> display_view = resolve_display_view(display, view);
    const std::string& d = display_view.first;
    const std::string& v = display_view.second;
    require_working_space();
    return cached(std::string("display_from_") + result_key(source) + "\n" + d + '\n' + v,
                  result_label(source, working_space_label()) + " -> display " + quoted(d) + ", view " + quoted(v),
                  [&]() -> OCIO::ConstTransformRcPtr {
                      if (is_data(config_.config->getDisplayViewColorSpaceName(d.c_str(), v.c_str()))) return nullptr;
                      return from_result(source,
                                         [&](const std::string& src) { return display_view_transform(src, d, v); });
                  });
}

}  // namespace darkroom::ocio
