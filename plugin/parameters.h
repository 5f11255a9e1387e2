// The node's parameters: their definitions (what a host shows) and reading them at a time
// into the settings core takes. They mirror the darkroom CLI's flags (README, "OpenFX
// plugin"): same names for the same quantities, same units, same defaults.
#pragma once

#include <stdexcept>
#include <string>

#include "core/develop.h"
#include "plugin/ofx_abi.h"

namespace darkroom::ofx {

// Everything a render needs from the parameters at one time.
struct NodeSettings {
    std::string film;   // a built-in stock id, or a stock file's path
    std::string paper;  // a built-in stock id, a stock file's path, or empty for none
    bool film_from_file = false, paper_from_file = false;
    DevelopSettings develop;  // develop.frame is the grain frame (0 with static grain)
    std::string ocio_config;  // empty: $OCIO, else the embedded config
    std::string input_space, output_space;
    // A plate's grain profile file (darkroom grain analyze/predict); when set it replaces the
    // stock's grain (develop.grain is false) and is added in the output colour space.
    std::string grain_profile;
    // The film frame is the project's format (false), or the Source image itself (true: a plate
    // whose format differs from the project's).
    bool film_frame_is_source = false;
};

// A parameter value the plugin cannot use; the message names the parameter by its label.
struct ParameterError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Defines every parameter and its group on a descriptor's parameter set.
void define_parameters(OfxParamSetHandle params);

// Reads and validates the parameters of an instance at `time`; throws ParameterError.
NodeSettings read_parameters(OfxImageEffectHandle instance, OfxTime time);

// The stock choices are indices into lists that grow as stocks are added, so each choice
// also saves its stock's id in a hidden parameter. On creating an instance (a saved node
// loaded), each choice is set to the option of its saved id, or the id recorded where none
// was saved; a saved stock this version does not have makes renders fail with its name until
// the user chooses another. When the user changes a choice (kOfxActionInstanceChanged), its
// id follows.
void restore_stock_choices(OfxImageEffectHandle instance);
void follow_stock_choice(OfxImageEffectHandle instance, const std::string& param, const std::string& reason);

}  // namespace darkroom::ofx
