// Quality tiers: one definition of how each stage is computed at each tier, shared by the
// command line, the plugin, the Python module and the benchmark.
//
//   reference  each stage from its definition: per-pixel spectral printing in double
//              precision, the MTF's full point spread function as a direct 2D sum,
//              halation as its exact Gaussian, grain as silver disks (a Boolean model,
//              Newson et al. 2017) rendered at the film's scale
//   high       the same spectral printing; the PSF as a sum of separable terms (every tap
//              within 1e-6 of the largest); grain as filtered Gaussian noise
//   fast       printing and viewing through 3D tables on layer densities, a compact PSF,
//              halation on a coarser grid, tabulated H&D curves
//   preview    as fast with smaller tables and kernels
//
// Every tier is measured against the reference by `darkroom bench`.
#pragma once

#include <optional>
#include <string>

namespace darkroom {

enum class Quality { reference, high, fast, preview };

enum class ScatterMethod { direct, separable, compact };
enum class GrainMethod { boolean_model, filtered_noise };

struct QualityTier {
    Quality quality;
    const char* name;
    ScatterMethod scatter;
    // compact PSF: the kernel radius limit in pixels (the PSF is windowed to it)
    int compact_scatter_radius_px;
    // Halation on a grid this many times coarser (1 = the pixel grid)
    int halation_decimation;
    GrainMethod grain;
    // Printing: 0 = per-pixel spectral integration; otherwise the nodes per axis of the 3D
    // tables from negative densities to paper exposure and from print densities to colour
    int print_table_nodes;
    // H&D curves: 0 = evaluated per pixel; otherwise samples of a uniform table in log H
    int curve_table_samples;
};

const QualityTier& quality_tier(Quality q);
const char* quality_name(Quality q);
std::optional<Quality> parse_quality(const std::string& name);
// The tiers in order, reference first.
constexpr Quality kQualities[] = {Quality::reference, Quality::high, Quality::fast, Quality::preview};

}  // namespace darkroom
