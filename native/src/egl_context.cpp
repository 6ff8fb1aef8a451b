#include "egl_context.h"

#include "device_selection.h"

#include <deferred/renderer.h>

#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

// EGL_EXT_device_query_name: not in libepoxy's generated headers.
#ifndef EGL_RENDERER_EXT
#define EGL_RENDERER_EXT 0x335F
#endif
// EGL_EXT_device_persistent_id, likewise.
#ifndef EGL_DEVICE_UUID_EXT
#define EGL_DEVICE_UUID_EXT 0x335C
#endif
using QueryDeviceBinary = EGLBoolean (*)(EGLDeviceEXT, EGLint, EGLint, void*, EGLint*);

namespace deferred {

const char* egl_error_name(EGLint error) {
    switch (error) {
        case EGL_SUCCESS: return "EGL_SUCCESS";
        case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
        case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
        case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
        case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
        case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
        case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
        case EGL_BAD_CURRENT_SURFACE: return "EGL_BAD_CURRENT_SURFACE";
        case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
        case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
        case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
        case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
        case EGL_BAD_NATIVE_PIXMAP: return "EGL_BAD_NATIVE_PIXMAP";
        case EGL_BAD_NATIVE_WINDOW: return "EGL_BAD_NATIVE_WINDOW";
        case EGL_CONTEXT_LOST: return "EGL_CONTEXT_LOST";
        default: return "unknown EGL error";
    }
}

namespace {

[[noreturn]] void fail(const std::string& step) {
    throw Error(step + " failed: " + egl_error_name(eglGetError()));
}

bool has_extension(const char* list, const char* name) {
    if (!list) return false;
    const std::size_t n = std::strlen(name);
    for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
        if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
    }
    return false;
}

// Tries eglInitialize on a display; returns false (and terminates nothing)
// when the display is unusable, so the cascade can move on.
bool try_initialize(EGLDisplay display) {
    if (display == EGL_NO_DISPLAY) return false;
    EGLint major = 0, minor = 0;
    return eglInitialize(display, &major, &minor) == EGL_TRUE;
}

// What each EGL device says of itself, for choose_egl_device.
std::vector<EglDeviceInfo> describe_devices(const std::vector<EGLDeviceEXT>& devices) {
    std::vector<EglDeviceInfo> infos;
    for (EGLDeviceEXT device : devices) {
        EglDeviceInfo info;
        const char* ext = eglQueryDeviceStringEXT(device, EGL_EXTENSIONS);
        info.software = has_extension(ext, "EGL_MESA_device_software");
        info.cuda_extension = has_extension(ext, "EGL_NV_device_cuda");
        if (info.cuda_extension) {
            EGLAttrib ordinal = -1;
            if (eglQueryDeviceAttribEXT(device, EGL_CUDA_DEVICE_NV, &ordinal) == EGL_TRUE && ordinal >= 0)
                info.cuda_ordinal = static_cast<int>(ordinal);
            else
                eglGetError();  // not visible to this process's CUDA: clear the error
        }
        if (has_extension(ext, "EGL_EXT_device_query_name")) {
            const char* renderer = eglQueryDeviceStringEXT(device, EGL_RENDERER_EXT);
            if (renderer) info.name = renderer;
        }
        if (has_extension(ext, "EGL_EXT_device_persistent_id")) {
            auto query = reinterpret_cast<QueryDeviceBinary>(eglGetProcAddress("eglQueryDeviceBinaryEXT"));
            unsigned char uuid[16] = {};
            EGLint size = 0;
            if (query && query(device, EGL_DEVICE_UUID_EXT, 16, uuid, &size) == EGL_TRUE && size == 16)
                info.uuid = format_gpu_uuid(uuid);
            else
                eglGetError();
        }
        if (info.name.empty() && has_extension(ext, "EGL_EXT_device_drm")) {
            const char* node = eglQueryDeviceStringEXT(device, EGL_DRM_DEVICE_FILE_EXT);
            if (node) info.name = node;
        }
        infos.push_back(std::move(info));
    }
    return infos;
}

struct DeviceDisplay {
    EGLDisplay display = EGL_NO_DISPLAY;
    std::string description, note;
};

// Step 1 of the cascade: the device choose_egl_device names. With an
// explicit index a missing device is an error (the caller asked for that
// GPU); without one, no usable device just means "fall through to
// surfaceless".
DeviceDisplay open_device_display(int requested) {
    DeviceDisplay result;
    const char* client_ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    const bool have_devices = has_extension(client_ext, "EGL_EXT_device_enumeration") ||
                              has_extension(client_ext, "EGL_EXT_device_base");
    const bool have_platform = has_extension(client_ext, "EGL_EXT_platform_device");
    if (!have_devices || !have_platform) {
        if (requested >= 0)
            throw Error("EGL device " + std::to_string(requested) +
                        " requested, but the EGL client has no EGL_EXT_platform_device");
        return result;
    }
    EGLint count = 0;
    if (!eglQueryDevicesEXT(0, nullptr, &count)) fail("eglQueryDevicesEXT");
    std::vector<EGLDeviceEXT> devices(static_cast<std::size_t>(count));
    if (count > 0 && !eglQueryDevicesEXT(count, devices.data(), &count)) fail("eglQueryDevicesEXT");
    devices.resize(static_cast<std::size_t>(count));

    const char* visible = std::getenv("CUDA_VISIBLE_DEVICES");
    const DeviceChoice choice = choose_egl_device(
        describe_devices(devices), visible ? std::optional<std::string>(visible) : std::nullopt, requested);
    result.note = choice.note;
    if (choice.egl_index < 0) return result;
    EGLDisplay d = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[choice.egl_index], nullptr);
    if (!try_initialize(d)) {
        // The default choice may fall through; a GPU asked for may not.
        if (requested >= 0 || visible) fail("eglInitialize on " + choice.description);
        return result;
    }
    result.display = d;
    result.description = choice.description;
    return result;
}

int device_index_from_environment(int device_index) {
    if (device_index >= 0) return device_index;
    const char* env = std::getenv("DEFERRED_EGL_DEVICE");
    if (!env || !*env) return -1;
    char* end = nullptr;
    long v = std::strtol(env, &end, 10);
    if (*end != '\0' || v < 0 || v > 1024)
        throw Error(std::string("DEFERRED_EGL_DEVICE='") + env + "' is not a device index");
    return static_cast<int>(v);
}

}  // namespace

EglContext::EglContext(int device_index) {
    const int requested = device_index_from_environment(device_index);

    DeviceDisplay choice = open_device_display(requested);
    display_ = choice.display;
    display_description_ = choice.description;
    device_note_ = choice.note;

    if (display_ == EGL_NO_DISPLAY) {
        const char* client_ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
        if (has_extension(client_ext, "EGL_MESA_platform_surfaceless")) {
            EGLDisplay d = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
            if (try_initialize(d)) {
                display_ = d;
                display_description_ = "Mesa surfaceless";
            }
        }
    }
    if (display_ == EGL_NO_DISPLAY) {
        EGLDisplay d = eglGetDisplay(EGL_DEFAULT_DISPLAY);
        if (d == EGL_NO_DISPLAY) fail("eglGetDisplay(EGL_DEFAULT_DISPLAY)");
        if (!try_initialize(d)) fail("eglInitialize on the default display");
        display_ = d;
        display_description_ = "default display";
    }

    // From here on, a failure must release the display (RAII by hand: the
    // destructor does not run for a half-built object).
    try {
        if (!eglBindAPI(EGL_OPENGL_API)) fail("eglBindAPI(EGL_OPENGL_API)");
        const EGLint config_attribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE,
                                         EGL_OPENGL_BIT, EGL_NONE};
        EGLConfig config = nullptr;
        EGLint num_configs = 0;
        // Surfaceless contexts need no config on Mesa, but ask for one when
        // the display offers it (some drivers reject EGL_NO_CONFIG_KHR).
        const char* display_ext = eglQueryString(display_, EGL_EXTENSIONS);
        const bool no_config = has_extension(display_ext, "EGL_KHR_no_config_context");
        if (!eglChooseConfig(display_, config_attribs, &config, 1, &num_configs) || num_configs < 1) {
            if (!no_config) fail("eglChooseConfig (no OpenGL-capable config)");
            config = EGL_NO_CONFIG_KHR;
        }
        if (!has_extension(display_ext, "EGL_KHR_surfaceless_context"))
            throw Error("EGL display (" + display_description_ +
                        ") lacks EGL_KHR_surfaceless_context, needed for headless rendering");
        const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4,
                                          EGL_CONTEXT_MINOR_VERSION, 5,
                                          EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                          EGL_NONE};
        context_ = eglCreateContext(display_, config, EGL_NO_CONTEXT, context_attribs);
        if (context_ == EGL_NO_CONTEXT) fail("eglCreateContext (OpenGL 4.5 core)");
        if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
            fail("eglMakeCurrent (surfaceless)");
    } catch (...) {
        if (context_ != EGL_NO_CONTEXT) eglDestroyContext(display_, context_);
        throw;  // the display stays initialised: see the destructor

    }
}

EglContext::~EglContext() {
    // Unbind before destroying, so the context really goes away now.
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (context_ != EGL_NO_CONTEXT) eglDestroyContext(display_, context_);
    // Never eglTerminate: EGL displays are per platform/device singletons, and
    // Blender's own EEVEE contexts live on the same surfaceless display in
    // background mode; terminating it would pull them away. Releasing our
    // context and thread state is enough for repeated create/destroy.
    eglReleaseThread();
}

}  // namespace deferred
