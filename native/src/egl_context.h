// Headless EGL display + OpenGL 4.5 core context, with no surface.
//
// Display cascade (Magnum's windowless EGL application, moderngl/glcontext):
//   1. EGL device platform (EGL_EXT_platform_device): one display per GPU;
//      device_selection.h chooses which (CUDA_VISIBLE_DEVICES, the Device
//      setting, else the first hardware device);
//   2. Mesa's surfaceless platform (EGL_MESA_platform_surfaceless);
//   3. eglGetDisplay(EGL_DEFAULT_DISPLAY).
// Every failing step throws deferred::Error naming the step and the EGL
// error by name. Must be created, used and destroyed on one thread.
#pragma once

#include <epoxy/egl.h>

#include <string>

namespace deferred {

class EglContext {
public:
    // device_index < 0: automatic choice (DEFERRED_EGL_DEVICE overrides).
    explicit EglContext(int device_index);
    ~EglContext();
    EglContext(const EglContext&) = delete;
    EglContext& operator=(const EglContext&) = delete;

    // Which step of the cascade produced the display, e.g. "EGL device 0 (hardware)".
    const std::string& display_description() const { return display_description_; }
    // A fallback taken while choosing the device (device_selection.h), or "".
    const std::string& device_note() const { return device_note_; }

private:
    EGLDisplay display_ = EGL_NO_DISPLAY;
    EGLContext context_ = EGL_NO_CONTEXT;
    std::string display_description_, device_note_;
};

const char* egl_error_name(EGLint error);

}  // namespace deferred
