// A minimal OpenFX host for testing the Darkroom bundle: it loads the binary with dlopen as a
// host does (OfxGetNumberOfPlugins, OfxGetPlugin, setHost, load, describe, describe in
// context, create instance), implements the suites the plugin fetches (property, image
// effect, parameter, memory, multithread, message), and renders windows of a source frame
// held in memory, asking the plugin for its regions of interest first and handing it only
// those pixels.
//
// Images are float, in OFX pixel coordinates (origin bottom left, rows going up).
#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "plugin/ofx_abi.h"

namespace testhost {

// A typed, named array (the host's half of the property suite).
struct Property {
    char type = 0;  // 's', 'i', 'd', 'p'
    std::vector<std::string> s;
    std::vector<int> i;
    std::vector<double> d;
    std::vector<void*> p;
};

struct PropertySet {
    std::map<std::string, Property> props;

    void set(const std::string& name, const std::string& v, int index = 0);
    void set(const std::string& name, int v, int index = 0);
    void set(const std::string& name, double v, int index = 0);
    std::string get_string(const std::string& name, int index = 0) const;
    int get_int(const std::string& name, int index = 0) const;
    double get_double(const std::string& name, int index = 0) const;
    bool has(const std::string& name) const { return props.count(name) != 0; }
    OfxPropertySetHandle handle() { return reinterpret_cast<OfxPropertySetHandle>(this); }
};

struct Param {
    std::string type, name;
    PropertySet props;
    std::vector<double> doubles;  // Double, Double3D
    int integer = 0;              // Integer, Boolean, Choice
    std::string text;             // String
};

struct ParamSet {
    PropertySet props;
    std::vector<std::unique_ptr<Param>> params;
    Param* find(const std::string& name) const;
};

// Float pixels with their bounds, rows bottom-up.
struct Frame {
    OfxRectI bounds{};
    int channels = 4;
    std::vector<float> pixels;

    Frame() = default;
    Frame(const OfxRectI& b, int nchannels, float fill = 0.0f);
    int width() const { return bounds.x2 - bounds.x1; }
    int height() const { return bounds.y2 - bounds.y1; }
    float* at(int x, int y) { return &pixels[((size_t)(y - bounds.y1) * width() + (x - bounds.x1)) * channels]; }
    const float* at(int x, int y) const {
        return &pixels[((size_t)(y - bounds.y1) * width() + (x - bounds.x1)) * channels];
    }
    // From / to top-down interleaved pixels (as image files hold them), at bounds (0, 0, w, h).
    static Frame from_top_down(const std::vector<float>& top_down, int width, int height, int channels);
    std::vector<float> to_top_down() const;
};

struct Clip {
    std::string name;
    PropertySet props;
    Frame* image = nullptr;            // what clipGetImage hands out (null: no image)
    std::string image_depth = kOfxBitDepthFloat;
    OfxRectD rod{};
};

struct Effect {
    PropertySet props;
    ParamSet params;
    std::map<std::string, std::unique_ptr<Clip>> clips;
    // Messages the plugin posted on this effect.
    std::string persistent_message;
    std::string persistent_message_type;  // kOfxMessageError, kOfxMessageWarning, ...
    std::vector<std::string> messages;
    // abort() answers 1 once it has been called this many times (-1: never).
    int abort_after = -1;
    std::atomic<int> abort_calls{0};
    OfxImageEffectHandle handle() { return reinterpret_cast<OfxImageEffectHandle>(this); }
};

struct RenderResult {
    OfxStatus status = kOfxStatOK;
    Frame output;  // bounds = the render window
};

class Instance;

// The loaded bundle, once per process.
class Plugin {
public:
    static Plugin& get();
    OfxPlugin* ofx() const { return plugin_; }
    Effect& descriptor() { return descriptor_; }
    Effect& context_descriptor() { return context_; }
    // A new instance; load_setup, when given, sets parameters before the plugin's create
    // instance action, as a host loading a saved node does.
    std::unique_ptr<Instance> create_instance(const std::function<void(Instance&)>& load_setup = {});
    OfxStatus call(const char* action, Effect* effect, PropertySet* in_args, PropertySet* out_args);

private:
    Plugin();
    void* library_ = nullptr;
    OfxPlugin* plugin_ = nullptr;
    Effect descriptor_, context_;
};

class Instance {
public:
    Instance(Plugin& plugin, const std::function<void(Instance&)>& load_setup);
    ~Instance();
    Effect& effect() { return effect_; }
    OfxStatus create_status() const { return create_status_; }

    void set_double(const std::string& name, double v);
    void set_double3(const std::string& name, double a, double b, double c);
    void set_int(const std::string& name, int v);  // integers, booleans and choices
    void set_string(const std::string& name, const std::string& v);
    int get_int(const std::string& name) const;
    std::string get_string(const std::string& name) const;
    // Tells the plugin the user changed a parameter (kOfxActionInstanceChanged), after set_*.
    OfxStatus user_edited(const std::string& name);
    // The index of a choice parameter's option whose label contains `text`; -1 if none.
    int choice_index(const std::string& name, const std::string& text) const;

    // The Source clip: its pixels at the render scale about to be used, its region of
    // definition in canonical coordinates (defaults to the frame at scale 1), its state.
    void set_source(const Frame& frame, const std::string& premultiplication = kOfxImagePreMultiplied);
    void set_source_rod(const OfxRectD& rod) { effect_.clips["Source"]->rod = rod; }
    // The project's format (canonical coordinates), as a host sets kOfxImageEffectPropProjectSize/Offset.
    void set_project(const OfxRectD& format) {
        effect_.props.set("OfxImageEffectPropProjectSize", format.x2 - format.x1, 0);
        effect_.props.set("OfxImageEffectPropProjectSize", format.y2 - format.y1, 1);
        effect_.props.set("OfxImageEffectPropProjectOffset", format.x1, 0);
        effect_.props.set("OfxImageEffectPropProjectOffset", format.y1, 1);
    }
    void disconnect_source();
    void set_source_depth(const std::string& depth) { effect_.clips["Source"]->image_depth = depth; }

    // Renders `window` (pixel coordinates at `scale`) the way a host does: clip preferences,
    // regions of interest, then render with only the pixels asked for. The output image is
    // the window itself unless `output_bounds` says otherwise.
    RenderResult render(double time, const OfxRectI& window, double scale = 1.0,
                        const OfxRectI* output_bounds = nullptr);
    // Renders the whole frame in tiles of the given size, stitched.
    RenderResult render_tiles(double time, const OfxRectI& frame, int tile_w, int tile_h, double scale = 1.0);
    OfxStatus is_identity(double time, std::string* clip = nullptr);
    // The Source region the plugin asks for to render `region` (canonical).
    OfxStatus region_of_interest(double time, const OfxRectD& region, double scale, OfxRectD* roi);

private:
    Plugin& plugin_;
    Effect effect_;
    Frame source_;
    OfxStatus create_status_ = kOfxStatOK;
};

// Host settings the tests change.
void set_cpu_count(unsigned n);
// Memory the plugin allocated through the memory suite and has not freed, and images it
// fetched and has not released.
long outstanding_allocations();
long outstanding_images();

}  // namespace testhost
