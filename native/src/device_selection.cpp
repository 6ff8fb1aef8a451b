#include "device_selection.h"

#include <deferred/renderer.h>

#include <algorithm>
#include <cctype>
#include <utility>

namespace deferred {

namespace {

std::string trimmed(const std::string& s) {
    std::size_t a = 0, b = s.size();
    while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
    while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
    return s.substr(a, b - a);
}

bool all_digits(const std::string& s) {
    return !s.empty() && s.size() <= 6 &&
           std::all_of(s.begin(), s.end(), [](char ch) { return std::isdigit(static_cast<unsigned char>(ch)); });
}

// CUDA_VISIBLE_DEVICES as CUDA reads it: comma-separated device indices or
// GPU-/MIG- UUIDs; the first entry that is neither ends the list (CUDA shows
// the devices before it and no others).
struct VisibleList {
    std::vector<int> indices;   // the integer entries, in order
    bool has_uuids = false;
    std::string first_invalid;  // the entry that ended the list, if one did
    std::size_t entries = 0;    // valid entries before it
};

VisibleList parse_visible_devices(const std::string& value) {
    VisibleList list;
    std::size_t start = 0;
    const std::string v = trimmed(value);
    if (v.empty()) return list;
    while (start <= v.size()) {
        std::size_t comma = v.find(',', start);
        if (comma == std::string::npos) comma = v.size();
        const std::string token = trimmed(v.substr(start, comma - start));
        if (all_digits(token)) {
            list.indices.push_back(std::stoi(token));
        } else if (token.rfind("GPU-", 0) == 0 || token.rfind("MIG-", 0) == 0) {
            list.has_uuids = true;
        } else {
            list.first_invalid = token;
            break;
        }
        ++list.entries;
        start = comma + 1;
    }
    return list;
}

std::string quoted(const std::string& s) { return "'" + s + "'"; }

std::string with_name(const std::string& what, const EglDeviceInfo& d) {
    return d.name.empty() ? what : what + " (" + d.name + ")";
}

// Why CUDA_VISIBLE_DEVICES leaves no GPU visible, as far as the value tells.
std::string why_none_visible(const std::string& value, std::size_t nvidia_count) {
    const VisibleList list = parse_visible_devices(value);
    const std::string prefix = "CUDA_VISIBLE_DEVICES=" + quoted(value) + " leaves this process no GPU: ";
    if (trimmed(value).empty())
        return prefix + "it is empty, so CUDA shows no device (did the scheduler give this job a GPU? "
                        "ask for one with --gres=gpu:1, or unset the variable)";
    if (list.entries == 0)
        return prefix + quoted(list.first_invalid) + " is neither a device index nor a GPU-/MIG- UUID";
    for (int index : list.indices)
        if (index >= static_cast<int>(nvidia_count))
            return prefix + "index " + std::to_string(index) + " is out of range: this machine has " +
                   std::to_string(nvidia_count) + " NVIDIA GPU(s), indices 0.." + std::to_string(int(nvidia_count) - 1);
    if (list.has_uuids) return prefix + "no GPU of this machine has the UUID it names";
    return prefix + "the driver maps none of the " + std::to_string(nvidia_count) +
           " NVIDIA EGL devices to a CUDA device this process sees";
}

DeviceChoice choose_without_nvidia(const std::vector<EglDeviceInfo>& devices,
                                   const std::optional<std::string>& cuda_visible_devices, int requested) {
    DeviceChoice choice;
    if (cuda_visible_devices)
        choice.note = "CUDA_VISIBLE_DEVICES=" + quoted(*cuda_visible_devices) +
                      " has no effect here: no EGL device is an NVIDIA CUDA device (EGL_NV_device_cuda)";
    const int count = static_cast<int>(devices.size());
    if (requested >= 0) {
        if (requested >= count)
            throw Error("EGL device " + std::to_string(requested) + " requested, but only " + std::to_string(count) +
                        " EGL device(s) exist (indices 0.." + std::to_string(count - 1) + ")");
        choice.egl_index = requested;
        choice.description = with_name("EGL device " + std::to_string(requested), devices[requested]);
        return choice;
    }
    // The first hardware device; software devices are llvmpipe, which the
    // surfaceless platform gives as well.
    for (int i = 0; i < count; ++i) {
        if (devices[i].software) continue;
        choice.egl_index = i;
        choice.description = with_name("EGL device " + std::to_string(i) + " (hardware)", devices[i]);
        return choice;
    }
    return choice;
}

}  // namespace

std::string format_gpu_uuid(const unsigned char bytes[16]) {
    static const char* hex = "0123456789abcdef";
    std::string out = "GPU-";
    for (int i = 0; i < 16; ++i) {
        if (i == 4 || i == 6 || i == 8 || i == 10) out += '-';
        out += hex[bytes[i] >> 4];
        out += hex[bytes[i] & 15];
    }
    return out;
}

DeviceChoice choose_egl_device(const std::vector<EglDeviceInfo>& devices,
                               const std::optional<std::string>& cuda_visible_devices, int requested) {
    std::vector<int> nvidia;
    for (int i = 0; i < static_cast<int>(devices.size()); ++i)
        if (devices[i].cuda_extension) nvidia.push_back(i);
    if (nvidia.empty()) return choose_without_nvidia(devices, cuda_visible_devices, requested);

    // (CUDA ordinal, EGL index) of every device the driver maps, in CUDA order.
    std::vector<std::pair<int, int>> mapped;
    for (int i : nvidia)
        if (devices[i].cuda_ordinal >= 0) mapped.emplace_back(devices[i].cuda_ordinal, i);
    std::sort(mapped.begin(), mapped.end());

    DeviceChoice choice;
    std::vector<int> visible;  // EGL indices, in the order this process's CUDA numbers them
    if (cuda_visible_devices) {
        const VisibleList list = parse_visible_devices(*cuda_visible_devices);
        if (!list.has_uuids && !list.indices.empty() && mapped.size() > list.indices.size()) {
            // The driver numbered every GPU as if the variable were unset:
            // apply the list here. CUDA stops at the first index out of range.
            choice.note = "the EGL driver maps all " + std::to_string(mapped.size()) +
                          " GPUs to CUDA ignoring CUDA_VISIBLE_DEVICES; its list is applied here";
            for (int index : list.indices) {
                auto it = std::find_if(mapped.begin(), mapped.end(),
                                       [&](const std::pair<int, int>& m) { return m.first == index; });
                if (it == mapped.end()) break;
                if (std::find(visible.begin(), visible.end(), it->second) == visible.end())
                    visible.push_back(it->second);
            }
        } else {
            for (const auto& m : mapped) visible.push_back(m.second);
        }
        if (visible.empty()) throw Error(why_none_visible(*cuda_visible_devices, nvidia.size()));
    } else if (mapped.empty()) {
        // No variable, and the driver maps nothing (a driver without CUDA):
        // the NVIDIA devices in EGL's order.
        choice.note = "no EGL device answered EGL_CUDA_DEVICE_NV; NVIDIA devices taken in EGL order";
        visible = nvidia;
    } else {
        for (const auto& m : mapped) visible.push_back(m.second);
    }

    const int position = requested >= 0 ? requested : 0;
    if (position >= static_cast<int>(visible.size()))
        throw Error("Device " + std::to_string(requested) + " requested, but " + std::to_string(visible.size()) +
                    " GPU(s) are visible to this process (indices 0.." + std::to_string(int(visible.size()) - 1) +
                    (cuda_visible_devices ? ", CUDA_VISIBLE_DEVICES=" + quoted(*cuda_visible_devices) : std::string()) +
                    ")");
    choice.egl_index = visible[position];
    const EglDeviceInfo& d = devices[choice.egl_index];
    std::string what = "EGL device " + std::to_string(choice.egl_index);
    if (d.cuda_ordinal >= 0) what += " = CUDA device " + std::to_string(position);
    if (cuda_visible_devices) what += " of CUDA_VISIBLE_DEVICES=" + quoted(*cuda_visible_devices);
    choice.description = with_name(what, d);
    if (!d.uuid.empty()) choice.description += " " + d.uuid;
    return choice;
}

}  // namespace deferred
