// darkroom plot STOCK -o chart.png|svg: a stock's data on four panels, as a data sheet
// shows it: characteristic curves, spectral sensitivities, dye densities and MTF.
#include <cmath>

#include "cli/chart.h"
#include "cli/commands.h"
#include "cli/image_io.h"
#include "core/stages/scatter.h"
#include "core/stock.h"

namespace darkroom::cli {

namespace {

std::vector<Chart> stock_charts(const Stock& stock) {
    const bool paper = stock.kind != StockKind::negative;  // (and slides: read in Status A, as viewed)
    Chart curves{stock.name + ": characteristic curves",
                 {"log10 exposure (lux-seconds)"},
                 {paper ? "diffuse density (Status A)" : "diffuse density (Status M)"},
                 {}};
    Chart sensitivity{"spectral sensitivity", {"wavelength (nm)"}, {"log10 relative sensitivity", false, -3.0, 0.2}, {}};
    Chart dyes{"spectral dye density", {"wavelength (nm)"}, {"density (dye: per unit net density)"}, {}};
    Chart mtf{"modulation transfer", {"cycles per mm", true}, {"response"}, {}};
    for (size_t i = 0; i < stock.layers.size(); ++i) {
        const Layer& l = stock.layers[i];
        std::array<float, 3> colour = stock.is_colour() ? channel_colour(l.name, int(i)) : chart_colour(0);
        ChartSeries curve{l.name, {}, {}, colour}, sens{l.name, {}, {}, colour}, dye{l.name, {}, {}, colour},
            response{l.name, {}, {}, colour};
        // The curve over its rising (a reversal film's falling) part, with half a log unit of
        // margin either side.
        double rise_start, rise_end;
        const Curve& c = l.density_curve;
        const bool falls = density_falls_with_exposure(stock.kind);
        if (!(falls ? c.first_x_down_to(c.y_max() - 0.01, &rise_start) : c.first_x_at(c.y_min() + 0.01, &rise_start)))
            rise_start = c.x_min();
        if (!(falls ? c.first_x_down_to(c.y_min() + 0.01, &rise_end) : c.first_x_at(c.y_max() - 0.01, &rise_end)))
            rise_end = c.x_max();
        for (double x = rise_start - 0.5; x <= rise_end + 0.5; x += 0.02) curve.x.push_back(x), curve.y.push_back(c(x));
        for (int k = 0; k < kSpectralSamples; ++k) {
            sens.x.push_back(wavelength_nm(k));
            sens.y.push_back(l.sensitivity[k] > 0 ? std::log10(l.sensitivity[k]) : NAN);
            dye.x.push_back(wavelength_nm(k));
            dye.y.push_back(l.dye_density[k]);
        }
        for (double f = 1; f <= 400; f *= 1.1) response.x.push_back(f), response.y.push_back(mtf_response(l.mtf, f));
        curves.series.push_back(curve);
        sensitivity.series.push_back(sens);
        dyes.series.push_back(dye);
        mtf.series.push_back(response);
    }
    if (stock.is_colour()) {
        ChartSeries base{"base + fog", {}, {}, chart_colour(3), true};
        for (int k = 0; k < kSpectralSamples; ++k) base.x.push_back(wavelength_nm(k)), base.y.push_back(stock.base_density[k]);
        dyes.series.push_back(base);
    }
    return {curves, sensitivity, dyes, mtf};
}

}  // namespace

void add_plot_command(CLI::App& app) {
    auto stock_id = std::make_shared<std::string>();
    auto output = std::make_shared<std::string>();
    CLI::App* cmd = app.add_subcommand("plot", "Draw a stock's curves, sensitivities, dyes and MTF");
    cmd->add_option("stock", *stock_id, "A built-in stock id (see 'darkroom stocks') or a stock file")->required();
    cmd->add_option("-o,--out", *output, "Chart file: .svg, or a raster format such as .png")->required();
    cmd->callback([stock_id, output] {
        Stock stock;
        try {
            stock = find_stock(*stock_id);
        } catch (const StockError& e) {
            throw UserError(e.what());
        }
        write_charts(*output, stock_charts(stock));
    });
}

}  // namespace darkroom::cli
