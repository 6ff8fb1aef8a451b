// Which EGL device a process renders on: the GPU its scheduler gave it.
//
// Cluster schedulers (Slurm's --gres=gpu:N, container runtimes) hand a
// process its GPUs through CUDA_VISIBLE_DEVICES. EGL enumerates every GPU of
// the machine in its own order, which is not CUDA's; EGL_NV_device_cuda maps
// an EGL device to the CUDA device enumerant of this process (the driver
// answers only for the devices CUDA_VISIBLE_DEVICES leaves visible, numbered
// as CUDA numbers them, so that the value can go to cuDeviceGet). The choice
// below is a pure function of what the EGL devices say, so that it is tested
// on machines without NVIDIA (tests/native/test_device_selection.cpp).
//
// Rules:
//   * With NVIDIA (some device has EGL_NV_device_cuda): the visible GPUs are
//     the devices that map to a CUDA ordinal, in CUDA's order; the Device
//     setting (requested >= 0) indexes that list, and the default is its
//     first entry, the device CUDA calls 0. A CUDA_VISIBLE_DEVICES that
//     leaves no device visible (empty, an unknown UUID, an index out of
//     range) is an error that names the value and why.
//     If the driver answered for more devices than an integer
//     CUDA_VISIBLE_DEVICES lists, it numbered the machine's GPUs without the
//     variable; the list is then applied here, in its order.
//   * Without NVIDIA: the choice of before (the Device setting indexes all
//     EGL devices; the default is the first hardware device, else none, so
//     that the caller falls through to Mesa's surfaceless platform); a
//     CUDA_VISIBLE_DEVICES is reported in the note as having no effect.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace deferred {

struct EglDeviceInfo {
    bool software = false;        // EGL_MESA_device_software (llvmpipe)
    bool cuda_extension = false;  // EGL_NV_device_cuda
    int cuda_ordinal = -1;        // EGL_CUDA_DEVICE_NV, -1 where the query failed
    std::string name;             // renderer or DRM node, for messages
    std::string uuid;             // "GPU-…" as nvidia-smi prints it (EGL_EXT_device_persistent_id), or ""
};

// The 16 bytes of EGL_DEVICE_UUID_EXT as nvidia-smi and CUDA_VISIBLE_DEVICES
// write a GPU's UUID: GPU-xxxxxxxx-xxxx-xxxx-xxxx-xxxxxxxxxxxx.
std::string format_gpu_uuid(const unsigned char bytes[16]);

struct DeviceChoice {
    int egl_index = -1;        // -1: no device-platform display; fall through
    std::string description;   // e.g. "EGL device 2 = CUDA device 0 (NVIDIA H100)"
    std::string note;          // a fallback taken, for the log; empty if none
};

// `cuda_visible_devices` is the variable's value, nullopt when unset.
// `requested` < 0 asks for the default. Throws deferred::Error.
DeviceChoice choose_egl_device(const std::vector<EglDeviceInfo>& devices,
                               const std::optional<std::string>& cuda_visible_devices, int requested);

}  // namespace deferred
