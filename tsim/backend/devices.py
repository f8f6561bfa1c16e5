"""What device a Taichi arch runs on: the CPU's model, the CUDA GPU's name, the Vulkan device Taichi
picks (and whether it is a software one, such as Mesa's lavapipe). Taichi does not say; each is
asked of the system or the driver directly (ctypes: libcuda, libvulkan), never by starting work on
the device. Every probe returns None rather than raising where the driver cannot be asked."""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import platform
import subprocess
import sys

from tsim.backend import tables as B

# VkPhysicalDeviceType: what a Vulkan driver says its device is
VK_TYPES = {0: "other", 1: "integrated GPU", 2: "discrete GPU", 3: "virtual GPU", 4: "CPU"}
VK_CPU = 4  # a software device: its shaders run on the CPU (lavapipe, SwiftShader)


def cpu_name() -> str:
    """The CPU's model ("Intel(R) Xeon(R) CPU @ 2.20GHz"), else the machine type ("x86_64")."""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                key, _, value = line.partition(":")
                if key.strip() in ("model name", "Model", "Hardware") and value.strip():
                    return value.strip()
    except OSError:
        pass
    if sys.platform == "darwin":
        try:
            out = subprocess.run(["sysctl", "-n", "machdep.cpu.brand_string"], capture_output=True,
                                 text=True, timeout=5).stdout.strip()
            if out:
                return out
        except (OSError, subprocess.SubprocessError):
            pass
    return platform.processor() or platform.machine() or "unknown CPU"


def cuda_name() -> str | None:
    """The name of the CUDA device Taichi uses (device 0 of those CUDA_VISIBLE_DEVICES leaves),
    from the driver (libcuda); None where it cannot be asked."""
    path = ctypes.util.find_library("cuda") or "libcuda.so.1"  # backend-seam: a library name
    try:
        cuda = ctypes.CDLL(path)
        dev = ctypes.c_int()
        name = ctypes.create_string_buffer(256)
        if cuda.cuInit(0) or cuda.cuDeviceGet(ctypes.byref(dev), 0) or cuda.cuDeviceGetName(name, 256, dev):
            return None
        return name.value.decode(errors="replace") or None
    except (OSError, AttributeError):
        return None


class _InstanceInfo(ctypes.Structure):
    _fields_ = [("sType", ctypes.c_int), ("pNext", ctypes.c_void_p), ("flags", ctypes.c_uint32),
                ("pApplicationInfo", ctypes.c_void_p), ("enabledLayerCount", ctypes.c_uint32),
                ("ppEnabledLayerNames", ctypes.c_void_p), ("enabledExtensionCount", ctypes.c_uint32),
                ("ppEnabledExtensionNames", ctypes.c_void_p)]


def vulkan_devices() -> list[dict] | None:
    """Every Vulkan device the loader finds, in its order: name, type (VK_TYPES), API minor
    version and whether it draws wide lines (what Taichi's choice weighs); None without Vulkan."""
    try:
        found = ctypes.util.find_library("vulkan")  # backend-seam: a library name
        vk = ctypes.CDLL("libvulkan.so.1" if sys.platform.startswith("linux") else
                         found or "libvulkan.so.1")
    except OSError:
        return None
    info = _InstanceInfo(sType=1)  # VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO; Vulkan 1.0, no layers
    instance = ctypes.c_void_p()
    try:
        if vk.vkCreateInstance(ctypes.byref(info), None, ctypes.byref(instance)):
            return None
    except AttributeError:
        return None
    try:
        count = ctypes.c_uint32()
        vk.vkEnumeratePhysicalDevices(instance, ctypes.byref(count), None)
        handles = (ctypes.c_void_p * count.value)()
        vk.vkEnumeratePhysicalDevices(instance, ctypes.byref(count), handles)
        found = []
        for handle in handles[:count.value]:
            props = ctypes.create_string_buffer(4096)  # VkPhysicalDeviceProperties: ~820 bytes
            vk.vkGetPhysicalDeviceProperties(ctypes.c_void_p(handle), props)
            features = (ctypes.c_uint32 * 64)()  # VkPhysicalDeviceFeatures: 55 VkBool32
            vk.vkGetPhysicalDeviceFeatures(ctypes.c_void_p(handle), features)
            api = int.from_bytes(props.raw[0:4], "little")
            found.append({"name": props.raw[20:276].split(b"\0")[0].decode(errors="replace"),
                          "type": int.from_bytes(props.raw[16:20], "little", signed=True),
                          "api_minor": (api >> 12) & 0x3FF, "wide_lines": bool(features[15])})
        return found
    finally:
        vk.vkDestroyInstance(instance, None)


def vulkan_choice(devices: list[dict]) -> dict | None:
    """The device Taichi 1.7 runs on among `devices`: TI_VISIBLE_DEVICE's, else the first of the
    highest score (taichi/rhi/vulkan/vulkan_device_creator.cpp: 1,000 for a compute queue, which
    every device here has, + 1,000 discrete GPU + 500 integrated + 100 wide lines + 100 per API
    minor version)."""
    visible = os.environ.get("TI_VISIBLE_DEVICE", "")
    if visible.isdigit() and int(visible) < len(devices):
        return devices[int(visible)]
    best, best_score = None, -1
    for d in devices:
        score = (1000 * (d["type"] == 2) + 500 * (d["type"] == 1) + 100 * d["wide_lines"]
                 + 100 * d["api_minor"])
        if score > best_score:
            best, best_score = d, score
    return best


def describe(backend: str) -> tuple[str, bool]:
    """(the device's name, whether it is software) for Taichi's arch name `backend` ("x64",
    "arm64", "cuda", "vulkan", "metal", ...)."""
    if backend in B.TAICHI_CPUS:
        return f"{backend}: {cpu_name()}", False
    if backend == B.CUDA:
        return cuda_name() or "a CUDA GPU (its name not readable)", False
    if backend == B.VULKAN:
        chosen = vulkan_choice(vulkan_devices() or [])
        if chosen is None:
            return "a Vulkan device (its name not readable)", False
        software = chosen["type"] == VK_CPU
        kind = "software, on the CPU" if software else VK_TYPES.get(chosen["type"], "other")
        return f"{chosen['name']}: {kind}", software
    if backend == B.METAL:
        return "the Mac's GPU", False
    return backend, False
