// The one render path of a look, for every front end (the program, the Python module and
// each of the plugin's row bands): colour in, the plan, colour out, a plate's grain, alpha,
// and the channels film has no business with passed through.
//
//   Renderer r(look, flag_name);                       // checks the look, resolves its colour
//   Plan plan = r.compile(frame_geometry(in), threads);
//   Image out = r.develop(plan, in, window, alpha);    // or to_working + render per band
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "core/develop.h"
#include "core/plate/grain_synthesis.h"
#include "look/colour.h"
#include "look/look.h"
#include "look/parameters.h"

namespace darkroom {

// The film and paper a look names: built-in ids or stock files ("none": no paper). A stock
// the look cannot use (a paper as the film) is the user's error, naming it by `name`.
Stock find_film(const Look& look, const Naming& name);
std::optional<Stock> find_paper(const Look& look, const Naming& name);

// The frame an input image is: its size, and grey when it has one or two channels (Y, Y+A),
// whose channel 0 the plan reads as R, G and B. Its window is in the film frame's
// coordinates, which is `film_width_px` wide and `film_height_px` high (0: the image's).
FrameGeometry frame_geometry(const ConstImageView& in, int film_width_px = 0, int film_height_px = 0);

// A grain profile file read and planned for synthesis; a bad file is the user's error.
GrainSynthesisPlan read_plate_grain(const std::string& profile_path, const GrainControls& controls = {});

class Renderer {
public:
    // Checks the look's settings together (validate), resolves its colour management and
    // reads its grain profile: a bad setting fails here, before any pixel, named by `name`.
    // With `verbose`, the colour management and each compiled plan are printed to stderr.
    Renderer(Look look, const Naming& name, bool verbose = false);

    const Look& look() const { return look_; }
    const ColourIO& colour() const { return colour_; }

    // The look's plan for a frame (its tables built on `threads` threads, 0: every core),
    // with `stocks` when the caller has read them (a plugin keeps them by file version).
    Plan compile(const FrameGeometry& frame, int threads) const;
    Plan compile(const FrameGeometry& frame, int threads, const Stock& film, const Stock* paper) const;

    // In place: the colour of `image` divided by the alpha in channel `premultiplied_alpha`
    // (-1: none) and converted to the working space (for a buffer the caller owns).
    void to_working(const ImageView& image, int premultiplied_alpha, int threads) const;
    // The colour `plan` reads for `out_window`: the input's pixels over input_window, in the
    // working space and straight (divided by the alpha in channel `premultiplied_alpha`,
    // -1: none). The input itself when nothing needs doing; else a copy in `buffer`.
    ConstImageView working_input(const Plan& plan, const ConstImageView& in, const Window& out_window,
                                 int premultiplied_alpha, Image& buffer, int threads) const;
    // Develops `out.window` of frame `frame` from `working` (working_input's): the plan, the
    // output conversion, the plate's grain (keyed like the film grain, by seed, frame and
    // absolute pixel, so a band is that band of the whole), then the channels past the
    // colour copied from `working` (alpha, depth, mattes) and the colour multiplied again by
    // the alpha. `out` has 3 colour channels and then the input's others.
    void render(const Plan& plan, const ConstImageView& working, const ImageView& out, int frame,
                int premultiplied_alpha, int threads) const;
    // Both, for a whole window: an image of max(3, input channels) channels.
    Image develop(const Plan& plan, const ConstImageView& in, const Window& out_window, int frame,
                  int premultiplied_alpha, int threads) const;

private:
    Look look_;
    Naming name_;
    bool verbose_;
    ColourIO colour_;
    std::shared_ptr<const GrainSynthesisPlan> plate_grain_;  // null: the stock's grain
};

// A plate's grain on an element whose colour may be premultiplied by the channel
// `premultiplied_alpha` (-1: none): grain on the light, not on light times coverage, so that
// where the element is transparent it adds none over the plate it is comped onto. `image`
// holds whole pixels, packed. A profile of other channels is the user's error, naming the file.
void apply_plate_grain_to_element(const GrainSynthesisPlan& grain, const std::string& profile_path,
                                  const ImageView& image, int premultiplied_alpha, uint64_t seed, int frame,
                                  int threads);

// What to warn of for the values that film reads and that are not finite, with how it takes
// them: in the pixels of `in` that the plan reads for `out_window` (the window and its halo),
// the colour's, and those of the alpha it is premultiplied by (-1: none). Depth, mattes and a
// straight alpha pass through untouched (a depth of +Inf is a render's background), so they
// are not counted. Empty when every such value is finite.
std::vector<std::string> non_finite_warnings(const Plan& plan, const ConstImageView& in, const Window& out_window,
                                             int premultiplied_alpha);

// The plans of one look for a sequence: compiled once per film frame width and grey input
// (a process's first compile takes about half a second, several times a 2K frame's develop)
// and moved to each frame's image window and grain (Plan::in_image, Plan::for_frame).
// Shared by the threads developing frames.
class PlanCache {
public:
    PlanCache(const Renderer& renderer, int threads) : renderer_(renderer), threads_(threads) {}
    Plan plan_for(const FrameGeometry& frame, int frame_number);

private:
    const Renderer& renderer_;
    int threads_;
    std::mutex mutex_;
    std::map<std::tuple<int, int, bool>, Plan> plans_;  // by the film frame's size and grey input
};

}  // namespace darkroom
