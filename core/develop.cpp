#include "core/develop.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/parallel.h"
#include "core/spectral.h"

namespace darkroom {

namespace {

constexpr double kMaxInput = 1e30;
// Reflection density of an 18 % grey: where the automatic print exposure puts mid grey.
const double kPrintAimDensity = std::log10(1.0 / 0.18);

std::string fmt(double v, int precision = 4) {
    std::ostringstream s;
    s.precision(precision);
    s << v;
    return s.str();
}

double sanitize(float v) {
    if (std::isnan(v)) return 0.0;
    return std::clamp(double(v), -kMaxInput, kMaxInput);
}

MaterialStages build_stages(const Stock& stock, double width_mm, int frame_width_px, const DevelopSettings& s,
                            uint32_t stream_base, const char* role, std::vector<std::string>& skipped) {
    MaterialStages m;
    m.stock = stock;
    m.pixel_pitch_um = width_mm * 1000.0 / frame_width_px;
    const Spectrum scene_light = illuminant_d65();
    for (size_t i = 0; i < stock.layers.size(); ++i) {
        const Layer& layer = stock.layers[i];
        std::string where = std::string(role) + " layer " + layer.name;
        m.rgb_weights.push_back(rgb_exposure_weights(layer.sensitivity, scene_light));
        if (!s.mtf) {
            m.scatter.push_back(ScatterKernel{0, {1.0f}});
            skipped.push_back("scatter (" + where + "): MTF turned off");
        } else {
            double deviation = mtf_deviation_to_nyquist(layer.mtf, m.pixel_pitch_um);
            ScatterKernel kernel = design_scatter_kernel(layer.mtf, m.pixel_pitch_um);
            m.scatter.push_back(kernel);
            if (deviation < kMtfNoOpTolerance)
                skipped.push_back("scatter (" + where + "): MTF within " + fmt(deviation, 2) + " of 1 up to Nyquist at " +
                                  fmt(m.pixel_pitch_um) + " um pitch");
            else if (kernel.is_identity())
                skipped.push_back("scatter (" + where + "): the point spread function is within one pixel at " +
                                  fmt(m.pixel_pitch_um) + " um pitch");
        }
        m.grain.push_back(std::nullopt);
        GrainModel g = design_grain(layer.grain, layer.density_curve.y_min(), m.pixel_pitch_um,
                                    NoiseKey{s.seed, s.frame, stream_base + uint32_t(i)});
        if (!s.grain)
            skipped.push_back("grain (" + where + "): grain turned off");
        else if (g.is_noop())
            skipped.push_back("grain (" + where + "): " + fmt(g.pixel_sigma_at_unit_density(), 2) +
                              " D per pixel is below " + fmt(GrainModel::kNoOpSigma, 2) + " at " +
                              fmt(m.pixel_pitch_um) + " um pitch");
        else
            m.grain.back() = g;
    }
    return m;
}

// One material: exposure planes (one per layer) on their window -> density planes on `out`.
std::vector<Plane> develop_material(const MaterialStages& m, std::vector<Plane> exposure, const Window& out,
                                    const Window& frame, int threads) {
    std::vector<Plane> density;
    for (size_t i = 0; i < exposure.size(); ++i) {
        Plane d(out);
        if (!m.scatter[i].is_identity()) {
            scatter(exposure[i], d, m.scatter[i], frame, threads);
        } else {
            for (int y = out.y0; y < out.y1; ++y)
                std::copy_n(exposure[i].row(y) + (out.x0 - exposure[i].window.x0), out.width(), d.row(y));
        }
        const Curve& curve = m.stock.layers[i].density_curve;
        for (float& v : d.pixels) v = float(curve(std::log10(double(v))));
        if (m.grain[i]) apply_grain(d, *m.grain[i], threads);
        density.push_back(std::move(d));
    }
    return density;
}

}  // namespace

double mid_grey_exposure_lux_s(double iso_speed) { return 0.65 * 12.5 / iso_speed; }

int MaterialStages::halo_px() const {
    int r = 0;
    for (const ScatterKernel& k : scatter) r = std::max(r, k.radius);
    return r;
}

Plan Plan::compile(const Stock& film, const Stock* paper, const DevelopSettings& settings,
                   const FrameGeometry& frame) {
    if (frame.width <= 0 || frame.height <= 0)
        throw std::invalid_argument("frame size " + std::to_string(frame.width) + "x" + std::to_string(frame.height) +
                                    " is empty");
    if (film.kind != StockKind::negative) throw std::invalid_argument("'" + film.id + "' is not a film stock");
    if (paper && paper->kind != StockKind::paper) throw std::invalid_argument("'" + paper->id + "' is not a paper");
    if (settings.output == OutputMode::print && !paper)
        throw std::invalid_argument("print output needs a paper (or choose the negative or density output)");
    for (double v : {settings.exposure_ev, settings.print_exposure_ev})
        if (!std::isfinite(v) || std::abs(v) > 64) throw std::invalid_argument("exposure must be within +-64 EV");
    for (double v : {settings.frame_width_mm, settings.print_width_mm})
        if (!std::isfinite(v) || v < 0 || v > 1e4) throw std::invalid_argument("frame and print widths must be 0-10000 mm");

    Plan p;
    p.settings_ = settings;
    p.frame_ = Window{0, 0, frame.width, frame.height};
    double film_width_mm = settings.frame_width_mm > 0 ? settings.frame_width_mm : film.frame_width_mm;
    p.film_stages_ = build_stages(film, film_width_mm, frame.width, settings, 0, "film", p.skipped_);
    p.film_exposure_scale_ = settings.input_units == InputUnits::lux_seconds
                                 ? 1.0
                                 : mid_grey_exposure_lux_s(film.iso_speed) / 0.18 * std::exp2(settings.exposure_ev);

    if (settings.output == OutputMode::print) {
        p.prints_ = true;
        double print_width_mm = settings.print_width_mm > 0 ? settings.print_width_mm : paper->frame_width_mm;
        p.paper_stages_ = build_stages(*paper, print_width_mm, frame.width, settings, 16, "paper", p.skipped_);
        // Automatic print exposure: the negative of a mid grey exposed at 0 EV prints at the aim density.
        const Curve& paper_curve = paper->layers[0].density_curve;
        double log_h_aim;
        if (!paper_curve.first_x_at(kPrintAimDensity, &log_h_aim))
            throw std::invalid_argument("paper '" + paper->id + "' never reaches the print aim density " +
                                        fmt(kPrintAimDensity));
        double grey_density = film.layers[0].density_curve(std::log10(mid_grey_exposure_lux_s(film.iso_speed)));
        p.enlarger_exposure_lux_s_ = std::pow(10.0, log_h_aim + grey_density) * std::exp2(settings.print_exposure_ev);
    } else if (paper) {
        p.skipped_.push_back("print: the " + std::string(settings.output == OutputMode::negative ? "negative" : "density") +
                             " output stops at the negative");
    }
    return p;
}

Window Plan::input_window(const Window& output) const {
    int halo = film_stages_.halo_px() + (prints_ ? paper_stages_.halo_px() : 0);
    return output.grown(halo).intersected(frame_);
}

void Plan::run(const ConstImageView& in, const ImageView& out, int threads) const {
    const Window out_window = out.window.intersected(frame_);
    if (out_window.empty()) return;
    if (!in.window.contains(input_window(out_window)))
        throw std::invalid_argument("the input image does not cover the window and its halo");
    if (in.channels < 1 || out.channels < 3) throw std::invalid_argument("need 1+ input channels and 3+ output channels");

    const Window film_out = out_window.grown(prints_ ? paper_stages_.halo_px() : 0).intersected(frame_);
    const Window film_in = film_out.grown(film_stages_.halo_px()).intersected(frame_);

    // Expose: input -> exposure in lux-seconds per film layer.
    std::vector<Plane> exposure;
    for (const auto& w : film_stages_.rgb_weights) {
        Plane h(film_in);
        parallel_for(film_in.y0, film_in.y1, threads, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y)
                for (int x = film_in.x0; x < film_in.x1; ++x) {
                    const float* px = in.at(x, y);
                    double rgb[3] = {sanitize(px[0]), sanitize(px[in.channels > 1 ? 1 : 0]),
                                     sanitize(px[in.channels > 2 ? 2 : 0])};
                    double e = (w[0] * rgb[0] + w[1] * rgb[1] + w[2] * rgb[2]) * film_exposure_scale_;
                    h.at(x, y) = float(std::clamp(e, 0.0, kMaxInput));
                }
        });
        exposure.push_back(std::move(h));
    }
    std::vector<Plane> film_density = develop_material(film_stages_, std::move(exposure), film_out, frame_, threads);

    // Convert, or print: light through the (spectrally neutral) silver negative onto the paper.
    std::vector<Plane> result;
    if (!prints_) {
        result = std::move(film_density);
        if (settings_.output == OutputMode::negative)
            for (Plane& d : result)
                for (float& v : d.pixels) v = float(std::pow(10.0, -double(v)));
    } else {
        Plane paper_exposure(film_out);
        for (size_t i = 0; i < paper_exposure.pixels.size(); ++i)
            paper_exposure.pixels[i] = float(enlarger_exposure_lux_s_ * std::pow(10.0, -double(film_density[0].pixels[i])));
        std::vector<Plane> planes(paper_stages_.stock.layers.size(), paper_exposure);
        result = develop_material(paper_stages_, std::move(planes), out_window, frame_, threads);
        for (Plane& d : result)
            for (float& v : d.pixels) v = float(std::pow(10.0, -double(v)));
    }

    // Black-and-white: one layer written to all three channels.
    bool copy_alpha = in.channels >= 4 && out.channels >= 4;
    parallel_for(out_window.y0, out_window.y1, threads, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = out_window.x0; x < out_window.x1; ++x) {
                float* px = out.at(x, y);
                for (int c = 0; c < 3; ++c) px[c] = result[std::min<size_t>(c, result.size() - 1)].at(x, y);
                if (copy_alpha) px[3] = in.at(x, y)[3];
            }
    });
}

std::vector<std::string> Plan::describe() const {
    std::vector<std::string> lines;
    auto material = [&](const MaterialStages& m, const char* role) {
        lines.push_back(std::string(role) + " " + m.stock.id + ": pixel pitch " + fmt(m.pixel_pitch_um) + " um");
        for (size_t i = 0; i < m.stock.layers.size(); ++i) {
            const Layer& l = m.stock.layers[i];
            const auto& w = m.rgb_weights[i];
            lines.push_back("  spectral sensitivity (" + l.name + "): exposure = " + fmt(w[0]) + " R + " + fmt(w[1]) +
                            " G + " + fmt(w[2]) + " B");
            if (!m.scatter[i].is_identity())
                lines.push_back("  scatter (" + l.name + "): MTF kernel radius " + std::to_string(m.scatter[i].radius) +
                                " px");
            lines.push_back("  develop (" + l.name + "): H&D curve, D " + fmt(l.density_curve.y_min()) + " to " +
                            fmt(l.density_curve.y_max()));
            if (m.grain[i])
                lines.push_back("  grain (" + l.name + "): " + fmt(m.grain[i]->pixel_sigma_at_unit_density()) +
                                " D per pixel at net density 1, filter radius " + std::to_string(m.grain[i]->radius) +
                                " px");
        }
    };
    if (settings_.input_units == InputUnits::lux_seconds)
        lines.push_back("expose: input pixels are exposures in lux-seconds");
    else
        lines.push_back("expose: scene-linear 0.18 -> " + fmt(0.18 * film_exposure_scale_) + " lux-s (ISO " +
                        fmt(film_stages_.stock.iso_speed) + ", " + fmt(settings_.exposure_ev) + " EV)");
    material(film_stages_, "film");
    if (prints_) {
        lines.push_back("print: enlarger gives " + fmt(enlarger_exposure_lux_s_) +
                        " lux-s through clear base (mid grey aimed at D " + fmt(kPrintAimDensity, 3) + ", " +
                        fmt(settings_.print_exposure_ev) + " EV)");
        material(paper_stages_, "paper");
        lines.push_back("convert: reflection density -> reflectance");
    } else {
        lines.push_back(settings_.output == OutputMode::negative ? "convert: density -> transmittance"
                                                                 : "convert: none (diffuse density written)");
    }
    for (const std::string& s : skipped_) lines.push_back("skipped " + s);
    return lines;
}

}  // namespace darkroom
