// The fast tiers' print grain: printing through one table leaves no place for the paper's
// grain, so it is folded into the film's (docs/model/print-grain-fold.md), and the paper's
// own grain and halation are left out of the plan. Part of the plan's internals.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "core/material_stages.h"

namespace darkroom {

// Raises each film layer's grain amplitude, and correlates the layers' grains, so that each
// channel of the viewed print has the grain variance of film and paper both, along the grey
// scale exposed at `exposure_scale` (lux-seconds per input unit). Only where the tier
// tabulates curves (`curve_table_bits`) and the film has three layers.
void fold_paper_grain(MaterialStages& film, const MaterialStages& paper, const PrintExposure& enlarger,
                      double exposure_scale, int curve_table_bits, int threads);

// The x >= 0 that minimises |A x - b| for a 3x3 A, with x_i held at 0 where !free[i]: 300
// sweeps of coordinate descent (the fold's equations at each grey level).
std::array<double, 3> nonnegative_least_squares(const double (&a)[3][3], const double (&b)[3], const bool (&free)[3]);
// The same of `count` systems into x[0 .. count), in vectors of systems (each lane sweeping
// its own, and stopping where that one would): bit for bit the values above, on every
// instruction set. Most of the fold's systems sweep all 300 times, one dependent division
// after another: a vector of them costs what one did.
struct LeastSquaresSystem {
    double a[3][3], b[3];
    bool free[3];
};
void nonnegative_least_squares(const LeastSquaresSystem* systems, int count, std::array<double, 3>* x);

// Leaves the paper's grain, halation and curve tables out of a plan that prints through one
// table, saying so in `skipped`.
void leave_out_paper_grain(MaterialStages& paper, const MaterialStages& film, std::vector<std::string>& skipped);

}  // namespace darkroom
