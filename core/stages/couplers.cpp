#include "core/stages/couplers.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/stages/filters.h"

namespace darkroom {

std::array<Curve, 3> curves_before_inhibition(const std::array<const Curve*, 3>& sheet, const CouplerMatrix& m,
                                              const std::array<std::string, 3>& layer_names) {
    std::vector<double> xs;  // every curve's samples: between them each u_i is linear
    for (const Curve* c : sheet) xs.insert(xs.end(), c->x.begin(), c->x.end());
    std::sort(xs.begin(), xs.end());
    xs.erase(std::unique(xs.begin(), xs.end()), xs.end());
    std::array<double, 3> d_min;
    for (size_t j = 0; j < 3; ++j) d_min[j] = sheet[j]->y_min();
    std::array<Curve, 3> before;
    for (size_t i = 0; i < 3; ++i) {
        std::vector<double> u, d;
        for (double x : xs) {
            double shift = 0;
            for (size_t j = 0; j < 3; ++j) shift += m[i][j] * ((*sheet[j])(x) - d_min[j]);
            const double at = x - shift;
            if (!u.empty() && !(at > u.back())) {
                // Where the sheet is flat (beyond its ends) a falling u only repeats its value.
                if ((*sheet[i])(x) == d.back()) continue;
                throw std::invalid_argument(
                    "the DIR couplers' inhibition of layer " + layer_names[i] + " at log H " + std::to_string(x) +
                    " grows faster than its exposure: no curve before inhibition reproduces the data sheet "
                    "(lower the dir-couplers amount)");
            }
            u.push_back(at);
            d.push_back((*sheet[i])(x));
        }
        before[i] = make_curve(std::move(u), std::move(d), "layer " + layer_names[i] + "'s curve before inhibition");
    }
    return before;
}

CouplerStage design_couplers(const Stock& stock, double amount, double spread, double pixel_pitch_um,
                             int curve_table_bits) {
    const DirCouplerSpec spec = stock_dir_couplers(stock);
    CouplerStage c;
    CouplerMatrix m;
    std::array<const Curve*, 3> sheet;
    std::array<std::string, 3> names;
    for (size_t i = 0; i < 3; ++i) {
        for (size_t j = 0; j < 3; ++j) {
            m[i][j] = spec.matrix[i][j] * amount;
            c.matrix[3 * i + j] = float(m[i][j]);
        }
        sheet[i] = &stock.layers[i].density_curve;
        names[i] = stock.layers[i].name;
        c.sheet[i] = *sheet[i];
        c.d_min[i] = sheet[i]->y_min();
        if (curve_table_bits > 0) c.sheet_tables.emplace_back(*sheet[i], curve_table_bits);
    }
    c.before = curves_before_inhibition(sheet, m, names);
    c.taps = pixel_integrated_gaussian(spec.diffusion_um * spread / pixel_pitch_um);
    return c;
}

void coupler_donor_row(const CouplerStage& c, size_t layer, const float* exposure, float* net_density, int width) {
    const float d_min = float(c.d_min[layer]);
    if (!c.sheet_tables.empty()) {
        c.sheet_tables[layer].apply_row(exposure, net_density, width);
    } else {
        for (int x = 0; x < width; ++x)
            net_density[x] = float(c.sheet[layer](std::log10(std::max(double(exposure[x]), 1e-30))));
    }
    for (int x = 0; x < width; ++x) net_density[x] -= d_min;
}

void inhibit_rows(const CouplerStage& c, float* const* exposure, const float* const* spread_net_density, int width) {
    constexpr float kLog2Of10 = 3.321928094887362f;
    const float* m = c.matrix.data();
    for (int x = 0; x < width; ++x) {
        const float n0 = spread_net_density[0][x], n1 = spread_net_density[1][x], n2 = spread_net_density[2][x];
        for (int i = 0; i < 3; ++i) {
            const float s = m[3 * i] * n0 + m[3 * i + 1] * n1 + m[3 * i + 2] * n2;
            exposure[i][x] *= std::exp2(-kLog2Of10 * s);
        }
    }
}

}  // namespace darkroom
