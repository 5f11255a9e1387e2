// The plan's internals: one material's run of the pipeline (the film's or the paper's),
// precomputed, shared by the plan's two runs (develop.cpp, develop_one_pass.cpp) and the
// print-grain fold (print_grain_fold.cpp). Not part of the API (core/develop.h).
#pragma once

#include <array>
#include <optional>
#include <vector>

#include "core/stages/couplers.h"
#include "core/stages/grain.h"
#include "core/stages/grain_boolean.h"
#include "core/stages/halation.h"
#include "core/stages/print.h"
#include "core/stages/scatter.h"
#include "core/stages/tables.h"
#include "core/stock.h"

namespace darkroom {

// One material's run of the pipeline, precomputed.
struct MaterialStages {
    Stock stock;
    double pixel_pitch_um = 0;
    std::vector<std::array<double, 3>> rgb_weights;  // per layer: exposure per unit RGB
    std::vector<std::optional<HalationKernel>> halation;  // per layer; none when skipped
    std::vector<ScatterKernel> scatter;              // per layer; identity when skipped
    std::vector<std::optional<GrainModel>> grain;    // per layer; none when skipped
    // per layer, the reference tier's grain instead (then `grain` is none)
    std::vector<std::optional<BooleanGrain>> boolean_grain;
    std::vector<LogAxisTable> curve_tables;          // per layer, when the tier tabulates curves
    std::optional<CouplerStage> couplers;            // a colour film's DIR couplers; none when off
    // The curve a layer develops its exposure through: the data sheet's, or with couplers
    // the curve before inhibition.
    const Curve& develop_curve(size_t layer) const {
        return couplers ? couplers->before[layer] : stock.layers[layer].density_curve;
    }
    // How far the densities of a pixel reach into the exposure, in pixels (the layers' most).
    int halo_px() const;
    // Layer i's densities on `out` need its developed densities here: grown by the reach of
    // its Boolean grain (which reads the densities around a pixel).
    Window developed_window(size_t layer, const Window& out, const Window& frame) const;
    // Every layer's developed window together: where the couplers, whose inhibition reaches
    // across the layers, develop them all.
    Window layers_developed_window(const Window& out, const Window& frame) const;
    // The exposure the layers' densities on `out` need: each layer's developed window, grown
    // by its scatter's input (scatter_input_window: whole tiles where the scatter is summed by
    // FFT) and its halation's reach, clipped to the frame; the union over the layers.
    Window input_window(const Window& out, const Window& frame) const;
};

// The paper's layer densities printed from the negative's (colour on colour): the enlarger's
// exposure developed through the paper's curves.
void print_densities(const PrintExposure& enlarger, const Stock& paper, const double* negative_density,
                     double* paper_density);

}  // namespace darkroom
