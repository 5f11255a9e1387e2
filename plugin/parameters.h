// The node's parameters, made from the look's parameter table (look/parameters.h): each
// row with an OpenFX name becomes a parameter of its type, default, range, help and group,
// so the node offers what the program and Python do. Beside them the node's own: static
// grain, what the film frame spans, and the look file it loads and saves.
#pragma once

#include <stdexcept>
#include <string>

#include "look/look.h"
#include "plugin/ofx_abi.h"

namespace darkroom::ofx {

// Everything a render needs from the parameters at one time.
struct NodeSettings {
    Look look;
    int frame = 0;  // the grain's frame (0 with static grain)
    // The stocks are files (their versions key the caches), not built-in ids.
    bool film_from_file = false, paper_from_file = false;
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

// Reads and checks the parameters of an instance at `time`; throws ParameterError.
NodeSettings read_parameters(OfxImageEffectHandle instance, OfxTime time);

// The stock choices are indices into lists that grow as stocks are added, so each choice
// also saves its stock's id in a hidden parameter. On creating an instance (a saved node
// loaded), each choice is set to the option of its saved id, or the id recorded where none
// was saved; a saved stock this version does not have makes renders fail with its name until
// the user chooses another.
void restore_stock_choices(OfxImageEffectHandle instance);

// kOfxActionInstanceChanged: a stock choice's id follows it; the Load look and Save look
// buttons read the Look file into the parameters or write the node's look at `time` to it.
void parameter_changed(OfxImageEffectHandle instance, const std::string& param, const std::string& reason,
                       OfxTime time);

}  // namespace darkroom::ofx
