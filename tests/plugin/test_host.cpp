#include "tests/plugin/test_host.h"

#include <dlfcn.h>

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <stdexcept>
#include <thread>

namespace testhost {

// --- Property sets ----------------------------------------------------------------------

void PropertySet::set(const std::string& name, const std::string& v, int index) {
    Property& p = props[name];
    p.type = 's';
    if ((int)p.s.size() <= index) p.s.resize(index + 1);
    p.s[index] = v;
}
void PropertySet::set(const std::string& name, int v, int index) {
    Property& p = props[name];
    p.type = 'i';
    if ((int)p.i.size() <= index) p.i.resize(index + 1);
    p.i[index] = v;
}
void PropertySet::set(const std::string& name, double v, int index) {
    Property& p = props[name];
    p.type = 'd';
    if ((int)p.d.size() <= index) p.d.resize(index + 1);
    p.d[index] = v;
}
std::string PropertySet::get_string(const std::string& name, int index) const { return props.at(name).s.at(index); }
int PropertySet::get_int(const std::string& name, int index) const { return props.at(name).i.at(index); }
double PropertySet::get_double(const std::string& name, int index) const { return props.at(name).d.at(index); }

Param* ParamSet::find(const std::string& name) const {
    for (const auto& p : params)
        if (p->name == name) return p.get();
    return nullptr;
}

namespace {

PropertySet* ps(OfxPropertySetHandle h) { return reinterpret_cast<PropertySet*>(h); }

// Getters find the property and check its type and index; setters create it.
template <typename T>
OfxStatus get_value(OfxPropertySetHandle h, const char* name, int index, char type,
                    std::vector<T> Property::*values, T* out) {
    if (!h || !name || !out) return kOfxStatErrBadHandle;
    auto it = ps(h)->props.find(name);
    if (it == ps(h)->props.end()) return kOfxStatErrUnknown;
    const Property& p = it->second;
    // A property is read with its own type only.
    if (p.type != type) return kOfxStatErrValue;
    if (index < 0 || index >= (int)(p.*values).size()) return kOfxStatErrBadIndex;
    *out = (p.*values)[index];
    return kOfxStatOK;
}

template <typename T>
OfxStatus set_value(OfxPropertySetHandle h, const char* name, int index, char type, std::vector<T> Property::*values,
                    T v) {
    if (!h || !name || index < 0) return kOfxStatErrBadHandle;
    Property& p = ps(h)->props[name];
    p.type = type;
    if ((int)(p.*values).size() <= index) (p.*values).resize(index + 1);
    (p.*values)[index] = v;
    return kOfxStatOK;
}

OfxStatus prop_set_pointer(OfxPropertySetHandle h, const char* n, int i, void* v) { return set_value(h, n, i, 'p', &Property::p, v); }
OfxStatus prop_set_string(OfxPropertySetHandle h, const char* n, int i, const char* v) {
    return v ? set_value(h, n, i, 's', &Property::s, std::string(v)) : kOfxStatErrValue;
}
OfxStatus prop_set_double(OfxPropertySetHandle h, const char* n, int i, double v) { return set_value(h, n, i, 'd', &Property::d, v); }
OfxStatus prop_set_int(OfxPropertySetHandle h, const char* n, int i, int v) { return set_value(h, n, i, 'i', &Property::i, v); }
OfxStatus prop_set_double_n(OfxPropertySetHandle h, const char* n, int count, const double* v) {
    for (int i = 0; i < count; ++i)
        if (OfxStatus s = prop_set_double(h, n, i, v[i])) return s;
    return kOfxStatOK;
}
OfxStatus prop_set_int_n(OfxPropertySetHandle h, const char* n, int count, const int* v) {
    for (int i = 0; i < count; ++i)
        if (OfxStatus s = prop_set_int(h, n, i, v[i])) return s;
    return kOfxStatOK;
}
OfxStatus prop_get_pointer(OfxPropertySetHandle h, const char* n, int i, void** v) { return get_value(h, n, i, 'p', &Property::p, v); }
OfxStatus prop_get_string(OfxPropertySetHandle h, const char* n, int i, char** v) {
    if (!h || !n || !v) return kOfxStatErrBadHandle;
    auto it = ps(h)->props.find(n);
    if (it == ps(h)->props.end()) return kOfxStatErrUnknown;
    if (it->second.type != 's') return kOfxStatErrValue;
    if (i < 0 || i >= (int)it->second.s.size()) return kOfxStatErrBadIndex;
    *v = const_cast<char*>(it->second.s[i].c_str());
    return kOfxStatOK;
}
OfxStatus prop_get_double(OfxPropertySetHandle h, const char* n, int i, double* v) { return get_value(h, n, i, 'd', &Property::d, v); }
OfxStatus prop_get_int(OfxPropertySetHandle h, const char* n, int i, int* v) { return get_value(h, n, i, 'i', &Property::i, v); }
OfxStatus prop_get_double_n(OfxPropertySetHandle h, const char* n, int count, double* v) {
    for (int i = 0; i < count; ++i)
        if (OfxStatus s = prop_get_double(h, n, i, &v[i])) return s;
    return kOfxStatOK;
}
OfxStatus prop_get_int_n(OfxPropertySetHandle h, const char* n, int count, int* v) {
    for (int i = 0; i < count; ++i)
        if (OfxStatus s = prop_get_int(h, n, i, &v[i])) return s;
    return kOfxStatOK;
}
OfxStatus prop_get_dimension(OfxPropertySetHandle h, const char* n, int* count) {
    if (!h || !n || !count) return kOfxStatErrBadHandle;
    auto it = ps(h)->props.find(n);
    if (it == ps(h)->props.end()) return kOfxStatErrUnknown;
    const Property& p = it->second;
    *count = (int)(p.type == 's' ? p.s.size() : p.type == 'i' ? p.i.size() : p.type == 'd' ? p.d.size() : p.p.size());
    return kOfxStatOK;
}
OfxStatus prop_reset(OfxPropertySetHandle h, const char* n) {
    if (!h || !n) return kOfxStatErrBadHandle;
    return ps(h)->props.erase(n) ? kOfxStatOK : kOfxStatErrUnknown;
}

const OfxPropertySuiteV1 property_suite = {
    prop_set_pointer, prop_set_string, prop_set_double, prop_set_int, nullptr, nullptr, prop_set_double_n,
    prop_set_int_n, prop_get_pointer, prop_get_string, prop_get_double, prop_get_int, nullptr, nullptr,
    prop_get_double_n, prop_get_int_n, prop_reset, prop_get_dimension};

// --- Image effect suite -----------------------------------------------------------------

Effect* fx(OfxImageEffectHandle h) { return reinterpret_cast<Effect*>(h); }
Clip* clip_of(OfxImageClipHandle h) { return reinterpret_cast<Clip*>(h); }

// An image handed to the plugin. Float images are the Frame's own pixels; 8- and 16-bit
// ones are converted copies, converted back into the Frame on release when written to.
struct HandedImage {
    PropertySet props;
    Frame* frame = nullptr;
    int bytes_per_sample = 4;
    bool written = false;  // the Output clip's image
    std::vector<unsigned char> converted;
};
std::mutex images_mutex;
std::map<PropertySet*, std::unique_ptr<HandedImage>> images_out;

int bytes_per_sample(const std::string& depth) {
    return depth == kOfxBitDepthByte ? 1 : depth == kOfxBitDepthShort ? 2 : 4;  // half: never read, see tests
}

// The suites' accessors: check the handle, hand out what it holds.
template <typename Handle, typename Out, typename Get>
OfxStatus hand_out(Handle h, Out* out, Get get) {
    if (!h || !out) return kOfxStatErrBadHandle;
    *out = get(h);
    return kOfxStatOK;
}

OfxStatus get_property_set(OfxImageEffectHandle h, OfxPropertySetHandle* out) {
    return hand_out(h, out, [](OfxImageEffectHandle e) { return fx(e)->props.handle(); });
}
OfxStatus get_param_set(OfxImageEffectHandle h, OfxParamSetHandle* out) {
    return hand_out(h, out, [](OfxImageEffectHandle e) { return reinterpret_cast<OfxParamSetHandle>(&fx(e)->params); });
}
OfxStatus clip_define(OfxImageEffectHandle h, const char* name, OfxPropertySetHandle* out) {
    if (!h || !name) return kOfxStatErrBadHandle;
    auto& clip = fx(h)->clips[name];
    if (clip) return kOfxStatErrExists;
    clip = std::make_unique<Clip>();
    clip->name = name;
    clip->props.set(kOfxPropName, std::string(name));
    if (out) *out = clip->props.handle();
    return kOfxStatOK;
}
OfxStatus clip_get_handle(OfxImageEffectHandle h, const char* name, OfxImageClipHandle* clip,
                          OfxPropertySetHandle* props) {
    if (!h || !name || !clip) return kOfxStatErrBadHandle;
    auto it = fx(h)->clips.find(name);
    if (it == fx(h)->clips.end()) return kOfxStatErrUnknown;
    *clip = reinterpret_cast<OfxImageClipHandle>(it->second.get());
    if (props) *props = it->second->props.handle();
    return kOfxStatOK;
}
OfxStatus clip_get_property_set(OfxImageClipHandle h, OfxPropertySetHandle* out) {
    return hand_out(h, out, [](OfxImageClipHandle c) { return clip_of(c)->props.handle(); });
}
OfxStatus clip_get_image(OfxImageClipHandle h, OfxTime, const OfxRectD*, OfxPropertySetHandle* out) {
    if (!h || !out) return kOfxStatErrBadHandle;
    Clip* clip = clip_of(h);
    if (!clip->image || !clip->props.get_int(kOfxImageClipPropConnected)) return kOfxStatFailed;
    auto handed = std::make_unique<HandedImage>();
    Frame& f = *clip->image;
    handed->frame = &f;
    handed->written = clip->name == kOfxImageEffectOutputClipName;
    handed->bytes_per_sample = bytes_per_sample(clip->image_depth);
    void* data = f.pixels.data();
    if (handed->bytes_per_sample < 4) {
        const float top = handed->bytes_per_sample == 1 ? 255.0f : 65535.0f;
        handed->converted.resize(f.pixels.size() * handed->bytes_per_sample);
        for (size_t i = 0; i < f.pixels.size(); ++i) {
            long v = std::lround(std::clamp(f.pixels[i], 0.0f, 1.0f) * top);
            if (handed->bytes_per_sample == 1)
                handed->converted[i] = (unsigned char)v;
            else
                reinterpret_cast<uint16_t*>(handed->converted.data())[i] = (uint16_t)v;
        }
        data = handed->converted.data();
    }
    PropertySet& image = handed->props;
    image.props[kOfxImagePropData].type = 'p';
    image.props[kOfxImagePropData].p = {data};
    for (int i = 0; i < 4; ++i) image.set(kOfxImagePropBounds, (&f.bounds.x1)[i], i);
    image.set(kOfxImagePropRowBytes, f.width() * f.channels * handed->bytes_per_sample);
    image.set(kOfxImageEffectPropPixelDepth, clip->image_depth);
    image.set(kOfxImageEffectPropComponents,
              std::string(f.channels == 4 ? kOfxImageComponentRGBA : kOfxImageComponentRGB));
    image.set(kOfxImageEffectPropPreMultiplication, clip->props.get_string(kOfxImageEffectPropPreMultiplication));
    image.set(kOfxImagePropPixelAspectRatio, 1.0);
    *out = image.handle();
    std::lock_guard<std::mutex> lock(images_mutex);
    images_out[&image] = std::move(handed);
    return kOfxStatOK;
}
OfxStatus clip_release_image(OfxPropertySetHandle h) {
    std::lock_guard<std::mutex> lock(images_mutex);
    auto it = images_out.find(ps(h));
    if (it == images_out.end()) return kOfxStatErrBadHandle;
    HandedImage& handed = *it->second;
    if (handed.written && handed.bytes_per_sample < 4) {
        std::vector<float>& px = handed.frame->pixels;
        for (size_t i = 0; i < px.size(); ++i)
            px[i] = handed.bytes_per_sample == 1 ? handed.converted[i] / 255.0f
                                                 : reinterpret_cast<const uint16_t*>(handed.converted.data())[i] / 65535.0f;
    }
    images_out.erase(it);
    return kOfxStatOK;
}
OfxStatus clip_get_rod(OfxImageClipHandle h, OfxTime, OfxRectD* out) {
    if (!h || !out) return kOfxStatErrBadHandle;
    if (!clip_of(h)->props.get_int(kOfxImageClipPropConnected)) return kOfxStatFailed;
    *out = clip_of(h)->rod;
    return kOfxStatOK;
}
int abort_render(OfxImageEffectHandle h) {
    Effect* e = fx(h);
    return e->abort_after >= 0 && e->abort_calls++ >= e->abort_after;
}

const OfxImageEffectSuiteV1 effect_suite = {get_property_set, get_param_set, clip_define, clip_get_handle,
                                            clip_get_property_set, clip_get_image, clip_release_image, clip_get_rod,
                                            abort_render, nullptr, nullptr, nullptr, nullptr};

// --- Parameter suite ---------------------------------------------------------------------

ParamSet* pset(OfxParamSetHandle h) { return reinterpret_cast<ParamSet*>(h); }
Param* param_of(OfxParamHandle h) { return reinterpret_cast<Param*>(h); }

bool is_int_type(const std::string& t) { return t == kOfxParamTypeInteger || t == kOfxParamTypeBoolean || t == kOfxParamTypeChoice; }
int dimensions(const std::string& t) { return t == kOfxParamTypeDouble3D ? 3 : 1; }

OfxStatus param_define(OfxParamSetHandle h, const char* type, const char* name, OfxPropertySetHandle* props) {
    if (!h || !type || !name) return kOfxStatErrBadHandle;
    if (pset(h)->find(name)) return kOfxStatErrExists;
    auto p = std::make_unique<Param>();
    p->type = type;
    p->name = name;
    p->props.set(kOfxPropName, std::string(name));
    p->props.set(kOfxPropType, std::string(type));
    if (props) *props = p->props.handle();
    pset(h)->params.push_back(std::move(p));
    return kOfxStatOK;
}
OfxStatus param_get_handle(OfxParamSetHandle h, const char* name, OfxParamHandle* param, OfxPropertySetHandle* props) {
    if (!h || !name || !param) return kOfxStatErrBadHandle;
    Param* p = pset(h)->find(name);
    if (!p) return kOfxStatErrUnknown;
    *param = reinterpret_cast<OfxParamHandle>(p);
    if (props) *props = p->props.handle();
    return kOfxStatOK;
}
OfxStatus param_set_get_property_set(OfxParamSetHandle h, OfxPropertySetHandle* out) {
    return hand_out(h, out, [](OfxParamSetHandle p) { return pset(p)->props.handle(); });
}
OfxStatus param_get_property_set(OfxParamHandle h, OfxPropertySetHandle* out) {
    return hand_out(h, out, [](OfxParamHandle p) { return param_of(p)->props.handle(); });
}
OfxStatus get_value_va(Param* p, va_list ap) {
    if (p->type == kOfxParamTypeString) {
        *va_arg(ap, char**) = const_cast<char*>(p->text.c_str());
    } else if (is_int_type(p->type)) {
        *va_arg(ap, int*) = p->integer;
    } else if (p->type == kOfxParamTypeDouble || p->type == kOfxParamTypeDouble3D) {
        for (int i = 0; i < dimensions(p->type); ++i) *va_arg(ap, double*) = p->doubles.at(i);
    } else {
        return kOfxStatErrUnsupported;
    }
    return kOfxStatOK;
}
// Parameters do not animate in this host: the value at any time is the value.
OfxStatus param_get_value_at_time(OfxParamHandle h, OfxTime time, ...) {
    if (!h) return kOfxStatErrBadHandle;
    va_list ap;
    va_start(ap, time);
    OfxStatus s = get_value_va(param_of(h), ap);
    va_end(ap);
    return s;
}

// Sets the value (the plugin sets its hidden stock ids and choices).
OfxStatus param_set_value(OfxParamHandle h, ...) {
    if (!h) return kOfxStatErrBadHandle;
    Param* p = param_of(h);
    va_list ap;
    va_start(ap, h);
    OfxStatus s = kOfxStatOK;
    if (p->type == kOfxParamTypeString)
        p->text = va_arg(ap, const char*);
    else if (is_int_type(p->type))
        p->integer = va_arg(ap, int);
    else if (p->type == kOfxParamTypeDouble || p->type == kOfxParamTypeDouble3D)
        for (int i = 0; i < dimensions(p->type); ++i) p->doubles.at(i) = va_arg(ap, double);
    else
        s = kOfxStatErrUnsupported;
    va_end(ap);
    return s;
}

// The plugin reads values at the render's time and sets values; it calls none of the others.
const OfxParameterSuiteV1 param_suite = {param_define, param_get_handle, param_set_get_property_set,
                                         param_get_property_set, nullptr, param_get_value_at_time,
                                         nullptr, nullptr, param_set_value, nullptr, nullptr, nullptr, nullptr,
                                         nullptr, nullptr, nullptr, nullptr, nullptr};

// --- Memory, threads, messages --------------------------------------------------------------

std::atomic<long> allocations{0};
OfxStatus memory_alloc(void*, size_t bytes, void** out) {
    if (!out) return kOfxStatErrBadHandle;
    *out = std::malloc(bytes ? bytes : 1);
    if (!*out) return kOfxStatErrMemory;
    ++allocations;
    return kOfxStatOK;
}
OfxStatus memory_free(void* p) {
    if (!p) return kOfxStatErrBadHandle;
    std::free(p);
    --allocations;
    return kOfxStatOK;
}
const OfxMemorySuiteV1 memory_suite = {memory_alloc, memory_free};

std::atomic<unsigned> cpu_count{4};
thread_local unsigned thread_index = 0;
thread_local bool spawned = false;

OfxStatus multi_thread(OfxThreadFunctionV1 func, unsigned n, void* arg) {
    if (spawned) return kOfxStatErrExists;
    std::vector<std::thread> threads;
    for (unsigned i = 0; i < n; ++i)
        threads.emplace_back([=] {
            thread_index = i;
            spawned = true;
            func(i, n, arg);
        });
    for (auto& t : threads) t.join();
    return kOfxStatOK;
}
OfxStatus multi_thread_num_cpus(unsigned* n) {
    *n = cpu_count;
    return kOfxStatOK;
}
OfxStatus multi_thread_index(unsigned* i) {
    *i = thread_index;
    return kOfxStatOK;
}
int multi_thread_is_spawned() { return spawned; }
OfxStatus mutex_create(OfxMutexHandle* m, int) {
    *m = reinterpret_cast<OfxMutexHandle>(new std::recursive_mutex);
    return kOfxStatOK;
}
OfxStatus mutex_destroy(const OfxMutexHandle m) {
    delete reinterpret_cast<std::recursive_mutex*>(m);
    return kOfxStatOK;
}
OfxStatus mutex_lock(const OfxMutexHandle m) {
    reinterpret_cast<std::recursive_mutex*>(m)->lock();
    return kOfxStatOK;
}
OfxStatus mutex_unlock(const OfxMutexHandle m) {
    reinterpret_cast<std::recursive_mutex*>(m)->unlock();
    return kOfxStatOK;
}
OfxStatus mutex_try_lock(const OfxMutexHandle m) {
    return reinterpret_cast<std::recursive_mutex*>(m)->try_lock() ? kOfxStatOK : kOfxStatFailed;
}
const OfxMultiThreadSuiteV1 thread_suite = {multi_thread, multi_thread_num_cpus, multi_thread_index,
                                            multi_thread_is_spawned, mutex_create, mutex_destroy,
                                            mutex_lock, mutex_unlock, mutex_try_lock};

std::mutex message_mutex;
std::string format_va(const char* format, va_list ap) {
    char text[4096];
    std::vsnprintf(text, sizeof text, format, ap);
    return text;
}
OfxStatus message(void* handle, const char*, const char*, const char* format, ...) {
    va_list ap;
    va_start(ap, format);
    std::string text = format_va(format, ap);
    va_end(ap);
    std::lock_guard<std::mutex> lock(message_mutex);
    if (handle) static_cast<Effect*>(handle)->messages.push_back(text);
    return kOfxStatOK;
}
OfxStatus set_persistent_message(void* handle, const char* type, const char*, const char* format, ...) {
    if (!handle) return kOfxStatErrBadHandle;
    va_list ap;
    va_start(ap, format);
    std::string text = format_va(format, ap);
    va_end(ap);
    std::lock_guard<std::mutex> lock(message_mutex);
    static_cast<Effect*>(handle)->persistent_message = text;
    static_cast<Effect*>(handle)->persistent_message_type = type ? type : "";
    return kOfxStatOK;
}
OfxStatus clear_persistent_message(void* handle) {
    if (!handle) return kOfxStatErrBadHandle;
    std::lock_guard<std::mutex> lock(message_mutex);
    static_cast<Effect*>(handle)->persistent_message.clear();
    static_cast<Effect*>(handle)->persistent_message_type.clear();
    return kOfxStatOK;
}
const OfxMessageSuiteV2 message_suite = {message, set_persistent_message, clear_persistent_message};

PropertySet host_props;

const void* fetch_suite(OfxPropertySetHandle, const char* name, int version) {
    std::string n = name ? name : "";
    if (n == kOfxPropertySuite && version == 1) return &property_suite;
    if (n == kOfxImageEffectSuite && version == 1) return &effect_suite;
    if (n == kOfxParameterSuite && version == 1) return &param_suite;
    if (n == kOfxMemorySuite && version == 1) return &memory_suite;
    if (n == kOfxMultiThreadSuite && version == 1) return &thread_suite;
    if (n == kOfxMessageSuite && (version == 1 || version == 2)) return &message_suite;
    return nullptr;
}

OfxHost host = {nullptr, fetch_suite};

OfxRectI pixel_rect(const OfxRectD& r, double scale) {
    return {(int)std::floor(r.x1 * scale), (int)std::floor(r.y1 * scale), (int)std::ceil(r.x2 * scale),
            (int)std::ceil(r.y2 * scale)};
}

OfxRectI intersect(const OfxRectI& a, const OfxRectI& b) {
    return {std::max(a.x1, b.x1), std::max(a.y1, b.y1), std::min(a.x2, b.x2), std::min(a.y2, b.y2)};
}

}  // namespace

void set_cpu_count(unsigned n) { cpu_count = n; }
long outstanding_allocations() { return allocations; }
long outstanding_images() {
    std::lock_guard<std::mutex> lock(images_mutex);
    return (long)images_out.size();
}

// --- Frames ---------------------------------------------------------------------------------

Frame::Frame(const OfxRectI& b, int nchannels, float fill)
    : bounds(b), channels(nchannels), pixels((size_t)std::max(0, b.x2 - b.x1) * std::max(0, b.y2 - b.y1) * nchannels, fill) {}

Frame Frame::from_top_down(const std::vector<float>& top_down, int width, int height, int channels) {
    Frame f({0, 0, width, height}, channels);
    for (int y = 0; y < height; ++y)
        std::copy_n(&top_down[(size_t)(height - 1 - y) * width * channels], (size_t)width * channels, f.at(0, y));
    return f;
}

std::vector<float> Frame::to_top_down() const {
    std::vector<float> out(pixels.size());
    for (int y = 0; y < height(); ++y)
        std::copy_n(at(bounds.x1, bounds.y1 + y), (size_t)width() * channels,
                    &out[(size_t)(height() - 1 - y) * width() * channels]);
    return out;
}

// --- Loading the plugin ----------------------------------------------------------------------

Plugin& Plugin::get() {
    static Plugin plugin;
    return plugin;
}

Plugin::Plugin() {
    host_props.set(kOfxPropName, std::string("org.darkroom.TestHost"));
    host_props.set(kOfxPropLabel, std::string("Darkroom test host"));
    host.host = host_props.handle();
    library_ = dlopen(DARKROOM_OFX_BUNDLE, RTLD_NOW | RTLD_LOCAL);
    if (!library_) throw std::runtime_error(std::string("dlopen: ") + dlerror());
    auto count = reinterpret_cast<OfxGetNumberOfPluginsFunction>(dlsym(library_, "OfxGetNumberOfPlugins"));
    auto get = reinterpret_cast<OfxGetPluginFunction>(dlsym(library_, "OfxGetPlugin"));
    if (!count || !get || count() < 1) throw std::runtime_error("the bundle exports no OFX plugin");
    plugin_ = get(0);
    plugin_->setHost(&host);
    if (plugin_->mainEntry(kOfxActionLoad, nullptr, nullptr, nullptr) != kOfxStatOK)
        throw std::runtime_error("the load action failed");
    if (call(kOfxActionDescribe, &descriptor_, nullptr, nullptr) != kOfxStatOK)
        throw std::runtime_error("the describe action failed");
    context_.props = descriptor_.props;
    PropertySet in;
    in.set(kOfxImageEffectPropContext, std::string(kOfxImageEffectContextFilter));
    if (call(kOfxImageEffectActionDescribeInContext, &context_, &in, nullptr) != kOfxStatOK)
        throw std::runtime_error("the describe-in-context action failed");
}

OfxStatus Plugin::call(const char* action, Effect* effect, PropertySet* in_args, PropertySet* out_args) {
    return plugin_->mainEntry(action, effect ? effect->handle() : nullptr, in_args ? in_args->handle() : nullptr,
                              out_args ? out_args->handle() : nullptr);
}

std::unique_ptr<Instance> Plugin::create_instance(const std::function<void(Instance&)>& load_setup) {
    return std::make_unique<Instance>(*this, load_setup);
}

// --- Instances ---------------------------------------------------------------------------------

Instance::Instance(Plugin& plugin, const std::function<void(Instance&)>& load_setup) : plugin_(plugin) {
    const Effect& desc = plugin.context_descriptor();
    effect_.props = desc.props;
    effect_.props.set(kOfxImageEffectPropContext, std::string(kOfxImageEffectContextFilter));
    // Parameters start at their defaults.
    for (const auto& d : desc.params.params) {
        auto p = std::make_unique<Param>(*d);
        const PropertySet& props = d->props;
        if (props.has(kOfxParamPropDefault)) {
            const Property& def = props.props.at(kOfxParamPropDefault);
            if (d->type == kOfxParamTypeString)
                p->text = def.s.at(0);
            else if (is_int_type(d->type))
                p->integer = def.i.at(0);
            else
                p->doubles = def.d;
        }
        effect_.params.params.push_back(std::move(p));
    }
    for (const auto& [name, clip] : desc.clips) {
        auto c = std::make_unique<Clip>(*clip);
        c->props.set(kOfxImageClipPropConnected, 1);
        c->props.set(kOfxImageEffectPropComponents, std::string(kOfxImageComponentRGBA));
        c->props.set(kOfxImageEffectPropPixelDepth, std::string(kOfxBitDepthFloat));
        c->props.set(kOfxImageEffectPropPreMultiplication, std::string(kOfxImagePreMultiplied));
        c->props.set(kOfxImagePropPixelAspectRatio, 1.0);
        effect_.clips[name] = std::move(c);
    }
    if (load_setup) load_setup(*this);
    create_status_ = plugin_.call(kOfxActionCreateInstance, &effect_, nullptr, nullptr);
}

Instance::~Instance() { plugin_.call(kOfxActionDestroyInstance, &effect_, nullptr, nullptr); }

void Instance::set_double(const std::string& name, double v) { effect_.params.find(name)->doubles.at(0) = v; }
void Instance::set_double3(const std::string& name, double a, double b, double c) {
    effect_.params.find(name)->doubles = {a, b, c};
}
void Instance::set_int(const std::string& name, int v) { effect_.params.find(name)->integer = v; }
void Instance::set_string(const std::string& name, const std::string& v) { effect_.params.find(name)->text = v; }
int Instance::get_int(const std::string& name) const { return effect_.params.find(name)->integer; }
std::string Instance::get_string(const std::string& name) const { return effect_.params.find(name)->text; }

OfxStatus Instance::user_edited(const std::string& name) {
    PropertySet args;
    args.set(kOfxPropType, std::string(kOfxTypeParameter));
    args.set(kOfxPropName, name);
    args.set(kOfxPropChangeReason, std::string(kOfxChangeUserEdited));
    args.set(kOfxPropTime, 0.0);
    args.set(kOfxImageEffectPropRenderScale, 1.0, 0);
    args.set(kOfxImageEffectPropRenderScale, 1.0, 1);
    return plugin_.call(kOfxActionInstanceChanged, &effect_, &args, nullptr);
}

int Instance::choice_index(const std::string& name, const std::string& text) const {
    const Property& options = effect_.params.find(name)->props.props.at(kOfxParamPropChoiceOption);
    for (size_t i = 0; i < options.s.size(); ++i)
        if (options.s[i].find(text) != std::string::npos) return (int)i;
    return -1;
}

void Instance::set_source(const Frame& frame, const std::string& premultiplication) {
    source_ = frame;
    Clip& clip = *effect_.clips["Source"];
    clip.image = &source_;
    clip.props.set(kOfxImageClipPropConnected, 1);
    clip.props.set(kOfxImageEffectPropComponents,
                   std::string(frame.channels == 4 ? kOfxImageComponentRGBA : kOfxImageComponentRGB));
    clip.props.set(kOfxImageEffectPropPreMultiplication, premultiplication);
    clip.rod = {(double)frame.bounds.x1, (double)frame.bounds.y1, (double)frame.bounds.x2, (double)frame.bounds.y2};
}

void Instance::disconnect_source() {
    Clip& clip = *effect_.clips["Source"];
    clip.props.set(kOfxImageClipPropConnected, 0);
    clip.image = nullptr;
}

OfxStatus Instance::region_of_interest(double time, const OfxRectD& region, double scale, OfxRectD* roi) {
    PropertySet in, out;
    in.set(kOfxPropTime, time);
    for (int i = 0; i < 2; ++i) in.set(kOfxImageEffectPropRenderScale, scale, i);
    for (int i = 0; i < 4; ++i) in.set(kOfxImageEffectPropRegionOfInterest, (&region.x1)[i], i);
    OfxStatus s = plugin_.call(kOfxImageEffectActionGetRegionsOfInterest, &effect_, &in, &out);
    if (s == kOfxStatOK)
        for (int i = 0; i < 4; ++i) (&roi->x1)[i] = out.get_double("OfxImageClipPropRoI_Source", i);
    return s;
}

RenderResult Instance::render(double time, const OfxRectI& window, double scale, const OfxRectI* output_bounds) {
    RenderResult result;
    Clip& source_clip = *effect_.clips["Source"];
    Clip& output_clip = *effect_.clips["Output"];

    // Clip preferences: the output's components and premultiplication.
    PropertySet prefs;
    if (plugin_.call(kOfxImageEffectActionGetClipPreferences, &effect_, nullptr, &prefs) == kOfxStatOK) {
        if (prefs.has("OfxImageClipPropComponents_Output"))
            output_clip.props.set(kOfxImageEffectPropComponents, prefs.get_string("OfxImageClipPropComponents_Output"));
        if (prefs.has(kOfxImageEffectPropPreMultiplication))
            output_clip.props.set(kOfxImageEffectPropPreMultiplication,
                                  prefs.get_string(kOfxImageEffectPropPreMultiplication));
    }

    // The source pixels handed over: only the region of interest (or the window by default).
    Frame given;
    if (source_clip.image) {
        OfxRectD region{window.x1 / scale, window.y1 / scale, window.x2 / scale, window.y2 / scale}, roi = region;
        if (region_of_interest(time, region, scale, &roi) != kOfxStatOK) roi = region;
        OfxRectI want = intersect(pixel_rect(roi, scale), source_.bounds);
        want = {want.x1, want.y1, std::max(want.x1, want.x2), std::max(want.y1, want.y2)};
        given = Frame(want, source_.channels);
        for (int y = want.y1; y < want.y2; ++y)
            for (int x = want.x1; x < want.x2; ++x) std::copy_n(source_.at(x, y), source_.channels, given.at(x, y));
        source_clip.image = &given;
    }

    // The output, filled with a value the plugin never writes.
    int out_channels = output_clip.props.get_string(kOfxImageEffectPropComponents) == kOfxImageComponentRGB ? 3 : 4;
    result.output = Frame(output_bounds ? *output_bounds : window, out_channels, -7.0f);
    output_clip.image = &result.output;
    output_clip.image_depth = source_clip.image_depth;

    PropertySet in;
    in.set(kOfxPropTime, time);
    for (int i = 0; i < 2; ++i) in.set(kOfxImageEffectPropRenderScale, scale, i);
    for (int i = 0; i < 4; ++i) in.set(kOfxImageEffectPropRenderWindow, (&window.x1)[i], i);
    result.status = plugin_.call(kOfxImageEffectActionRender, &effect_, &in, nullptr);
    if (source_clip.image) source_clip.image = &source_;
    output_clip.image = nullptr;
    return result;
}

RenderResult Instance::render_tiles(double time, const OfxRectI& frame, int tile_w, int tile_h, double scale) {
    RenderResult all;
    all.output = Frame(frame, 4, -7.0f);
    for (int y = frame.y1; y < frame.y2; y += tile_h)
        for (int x = frame.x1; x < frame.x2; x += tile_w) {
            OfxRectI tile{x, y, std::min(x + tile_w, frame.x2), std::min(y + tile_h, frame.y2)};
            RenderResult r = render(time, tile, scale);
            if (r.status != kOfxStatOK) return r;
            all.output.channels = r.output.channels;
            all.output.pixels.resize((size_t)all.output.width() * all.output.height() * r.output.channels);
            for (int ty = tile.y1; ty < tile.y2; ++ty)
                for (int tx = tile.x1; tx < tile.x2; ++tx)
                    std::copy_n(r.output.at(tx, ty), r.output.channels, all.output.at(tx, ty));
        }
    return all;
}

OfxStatus Instance::is_identity(double time, std::string* clip) {
    PropertySet in, out;
    in.set(kOfxPropTime, time);
    for (int i = 0; i < 2; ++i) in.set(kOfxImageEffectPropRenderScale, 1.0, i);
    OfxRectD rod = effect_.clips["Source"]->rod;
    for (int i = 0; i < 4; ++i) in.set(kOfxImageEffectPropRenderWindow, (int)(&rod.x1)[i], i);
    OfxStatus s = plugin_.call(kOfxImageEffectActionIsIdentity, &effect_, &in, &out);
    if (s == kOfxStatOK && clip) *clip = out.get_string(kOfxPropName);
    return s;
}

}  // namespace testhost
