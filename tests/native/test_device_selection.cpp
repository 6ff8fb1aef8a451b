// Which EGL device a process renders on (device_selection.h): the GPU that
// CUDA_VISIBLE_DEVICES gives it, on device lists shaped as NVIDIA's and
// Mesa's EGL report them. The real EGL of this machine is exercised by
// Context.* and by DeviceSelection.ThisMachine below.
#include "device_selection.h"

#include <deferred/renderer.h>

#include <gtest/gtest.h>

#include <cstdlib>

using namespace deferred;

namespace {

EglDeviceInfo nvidia(int cuda_ordinal, const char* name) {
    EglDeviceInfo d;
    d.cuda_extension = true;
    d.cuda_ordinal = cuda_ordinal;
    d.name = name;
    return d;
}

EglDeviceInfo mesa_software() {
    EglDeviceInfo d;
    d.software = true;
    d.name = "llvmpipe";
    return d;
}

// A 4-GPU node as NVIDIA's EGL enumerates it: EGL order is not CUDA order.
// With CUDA_VISIBLE_DEVICES=2 the driver answers EGL_CUDA_DEVICE_NV only for
// the one visible GPU, as CUDA device 0.
std::vector<EglDeviceInfo> node_seen_with(std::vector<int> ordinals_by_egl_index) {
    std::vector<EglDeviceInfo> devices;
    const char* names[] = {"gpu-a", "gpu-b", "gpu-c", "gpu-d"};
    for (std::size_t i = 0; i < ordinals_by_egl_index.size(); ++i)
        devices.push_back(nvidia(ordinals_by_egl_index[i], names[i]));
    devices.push_back(mesa_software());
    return devices;
}

std::string error_of(const std::vector<EglDeviceInfo>& devices, const char* visible, int requested) {
    try {
        choose_egl_device(devices, visible ? std::optional<std::string>(visible) : std::nullopt, requested);
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST(DeviceSelection, DefaultIsTheDeviceCudaCallsZeroNotEglsFirst) {
    // No variable: CUDA numbers all four; EGL lists CUDA 2 first.
    auto devices = node_seen_with({2, 0, 3, 1});
    DeviceChoice c = choose_egl_device(devices, std::nullopt, -1);
    EXPECT_EQ(c.egl_index, 1);
    EXPECT_NE(c.description.find("CUDA device 0"), std::string::npos) << c.description;
    EXPECT_NE(c.description.find("gpu-b"), std::string::npos) << c.description;
    // The Device setting indexes CUDA's order.
    EXPECT_EQ(choose_egl_device(devices, std::nullopt, 1).egl_index, 3);
    EXPECT_EQ(choose_egl_device(devices, std::nullopt, 3).egl_index, 2);
    EXPECT_TRUE(c.note.empty());
}

TEST(DeviceSelection, SchedulerGivenGpuIsChosen) {
    // Slurm gave this task physical GPU 3, which EGL lists third: the driver
    // answers only for it, as CUDA device 0.
    auto devices = node_seen_with({-1, -1, 0, -1});
    DeviceChoice c = choose_egl_device(devices, std::string("3"), -1);
    EXPECT_EQ(c.egl_index, 2);
    EXPECT_NE(c.description.find("CUDA_VISIBLE_DEVICES='3'"), std::string::npos) << c.description;
    // Two GPUs given, "3,1": CUDA 0 is physical 3, CUDA 1 physical 1.
    auto two = node_seen_with({-1, 1, 0, -1});
    EXPECT_EQ(choose_egl_device(two, std::string("3,1"), -1).egl_index, 2);
    EXPECT_EQ(choose_egl_device(two, std::string("3,1"), 1).egl_index, 1);
    // UUIDs are the driver's business; the mapping it answers is used.
    auto by_uuid = node_seen_with({-1, 0, -1, -1});
    EXPECT_EQ(choose_egl_device(by_uuid, std::string("GPU-5d1a7f2e-0000-0000-0000-000000000000"), -1).egl_index, 1);
}

TEST(DeviceSelection, DeviceSettingIndexesWithinTheVisibleGpus) {
    auto two = node_seen_with({-1, 1, 0, -1});
    const std::string msg = error_of(two, "3,1", 2);
    EXPECT_NE(msg.find("2 GPU(s) are visible"), std::string::npos) << msg;
    EXPECT_NE(msg.find("CUDA_VISIBLE_DEVICES='3,1'"), std::string::npos) << msg;
}

TEST(DeviceSelection, DriverThatIgnoresTheVariableGetsTheListAppliedHere) {
    // Every GPU answers with its machine-wide ordinal although the variable
    // names one: the list is applied here, in its order.
    auto devices = node_seen_with({2, 0, 3, 1});
    DeviceChoice c = choose_egl_device(devices, std::string("3"), -1);
    EXPECT_EQ(c.egl_index, 2);  // the device whose ordinal is 3
    EXPECT_FALSE(c.note.empty());
    DeviceChoice second = choose_egl_device(devices, std::string("1,2"), 1);
    EXPECT_EQ(second.egl_index, 0);  // CUDA 1 of "1,2" is machine ordinal 2
    // As CUDA does, the list ends at the first index out of range.
    const std::string msg = error_of(devices, "7,1", -1);
    EXPECT_NE(msg.find("index 7 is out of range"), std::string::npos) << msg;
}

TEST(DeviceSelection, VariableLeavingNoGpuIsAClearError) {
    auto none_visible = node_seen_with({-1, -1, -1, -1});
    std::string msg = error_of(none_visible, "", -1);
    EXPECT_NE(msg.find("it is empty"), std::string::npos) << msg;
    msg = error_of(none_visible, "  ", -1);
    EXPECT_NE(msg.find("it is empty"), std::string::npos) << msg;
    msg = error_of(none_visible, "gpu0", -1);
    EXPECT_NE(msg.find("'gpu0' is neither a device index nor a GPU-/MIG- UUID"), std::string::npos) << msg;
    msg = error_of(none_visible, "9", -1);
    EXPECT_NE(msg.find("index 9 is out of range: this machine has 4 NVIDIA GPU(s)"), std::string::npos) << msg;
    msg = error_of(none_visible, "GPU-00000000-dead-beef-0000-000000000000", -1);
    EXPECT_NE(msg.find("no GPU of this machine has the UUID"), std::string::npos) << msg;
    // Every message names the variable and its value.
    EXPECT_NE(msg.find("CUDA_VISIBLE_DEVICES='GPU-"), std::string::npos) << msg;
}

TEST(DeviceSelection, WithoutNvidiaTheChoiceOfBeforeStandsAndTheVariableIsNoted) {
    std::vector<EglDeviceInfo> mesa = {mesa_software()};
    DeviceChoice c = choose_egl_device(mesa, std::string("0"), -1);
    EXPECT_EQ(c.egl_index, -1);  // falls through to the surfaceless platform
    EXPECT_NE(c.note.find("has no effect here"), std::string::npos) << c.note;
    for (const char* value : {"", "7", "nonsense"})
        EXPECT_NO_THROW(choose_egl_device(mesa, std::string(value), -1)) << value;
    EXPECT_TRUE(choose_egl_device(mesa, std::nullopt, -1).note.empty());
    // An explicit index still names EGL devices, and a missing one is an error.
    EXPECT_EQ(choose_egl_device(mesa, std::nullopt, 0).egl_index, 0);
    const std::string msg = error_of(mesa, nullptr, 3);
    EXPECT_NE(msg.find("EGL device 3 requested, but only 1 EGL device(s) exist"), std::string::npos) << msg;
    // A hardware device is preferred over the software one.
    EglDeviceInfo amd;
    amd.name = "/dev/dri/card1";
    std::vector<EglDeviceInfo> mixed = {mesa_software(), amd};
    EXPECT_EQ(choose_egl_device(mixed, std::nullopt, -1).egl_index, 1);
}

TEST(DeviceSelection, UuidIsWrittenAsNvidiaSmiWritesIt) {
    const unsigned char bytes[16] = {0x5d, 0x1a, 0x7f, 0x2e, 0x01, 0x23, 0x45, 0x67,
                                     0x89, 0xab, 0xcd, 0xef, 0x00, 0x10, 0x20, 0xff};
    EXPECT_EQ(format_gpu_uuid(bytes), "GPU-5d1a7f2e-0123-4567-89ab-cdef001020ff");
}

// On the machine the suite runs on: the chosen device is the one CUDA calls 0
// when NVIDIA is present, else the fallback is noted. On a GPU machine,
// DEFERRED_EXPECT_GPU_UUID (nvidia-smi's UUID of the GPU CUDA_VISIBLE_DEVICES
// names first) checks that it is the GPU CUDA names, and DEFERRED_EXPECT_GPU
// a part of its name:
//   CUDA_VISIBLE_DEVICES=1
//   DEFERRED_EXPECT_GPU_UUID=$(nvidia-smi -i 1 --query-gpu=uuid --format=csv,noheader)
//   build/tests/deferred_native_tests --gtest_filter='DeviceSelection.*'
// (nvidia-smi numbers GPUs by PCI bus, as CUDA does with
// CUDA_DEVICE_ORDER=PCI_BUS_ID and on nodes of identical GPUs.)
TEST(DeviceSelection, ThisMachine) {
    Renderer r;
    const GLInfo& info = r.gl_info();
    std::printf("device: %s | %s | note: %s\n", info.display.c_str(), info.renderer.c_str(),
                info.device_note.empty() ? "-" : info.device_note.c_str());
    if (const char* expect = std::getenv("DEFERRED_EXPECT_GPU_UUID")) {
        EXPECT_NE(info.display.find(expect), std::string::npos) << info.display;
    }
    if (const char* expect = std::getenv("DEFERRED_EXPECT_GPU")) {
        EXPECT_NE(info.renderer.find(expect), std::string::npos) << info.renderer;
    }
    if (std::getenv("CUDA_VISIBLE_DEVICES") && info.display.find("CUDA device") == std::string::npos) {
        EXPECT_NE(info.device_note.find("CUDA_VISIBLE_DEVICES"), std::string::npos) << info.device_note;
    }
}
