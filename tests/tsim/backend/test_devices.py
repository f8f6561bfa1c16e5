"""Naming the device a backend runs on (issue 45, item 4): the Vulkan device Taichi picks by its
own rule, and the one line `sgr evolve`, `bench` and `validate` start with."""

from tsim.backend import devices, runtime

LLVMPIPE = {"name": "llvmpipe (LLVM 15.0.6, 256 bits)", "type": devices.VK_CPU, "api_minor": 3,
            "wide_lines": True}
DISCRETE = {"name": "NVIDIA H200", "type": 2, "api_minor": 3, "wide_lines": True}
INTEGRATED = {"name": "Intel(R) UHD Graphics", "type": 1, "api_minor": 0, "wide_lines": False}


def test_taichi_picks_a_hardware_gpu_over_lavapipe_whatever_the_order(monkeypatch):
    """Taichi's score (vulkan_device_creator.cpp): discrete +1000, integrated +500, wide lines and
    each API minor version +100; an integrated Vulkan 1.0 GPU without wide lines still beats
    llvmpipe's Vulkan 1.3 with them (500 against 400)."""
    monkeypatch.delenv("TI_VISIBLE_DEVICE", raising=False)
    assert devices.vulkan_choice([LLVMPIPE, DISCRETE]) is DISCRETE
    assert devices.vulkan_choice([DISCRETE, LLVMPIPE]) is DISCRETE
    assert devices.vulkan_choice([LLVMPIPE, INTEGRATED]) is INTEGRATED
    assert devices.vulkan_choice([LLVMPIPE]) is LLVMPIPE
    assert devices.vulkan_choice([]) is None


def test_ti_visible_device_chooses_the_device(monkeypatch):
    monkeypatch.setenv("TI_VISIBLE_DEVICE", "0")
    assert devices.vulkan_choice([LLVMPIPE, DISCRETE]) is LLVMPIPE
    monkeypatch.setenv("TI_VISIBLE_DEVICE", "7")  # not a device: Taichi falls back to its score
    assert devices.vulkan_choice([LLVMPIPE, DISCRETE]) is DISCRETE


def test_the_backend_line_names_arch_cpu_model_and_precision():
    runtime.init()
    line = runtime.describe()
    name, software = runtime.device()
    assert line == f"backend: cpu ({name}), {runtime.precision()}"
    assert not software and name.startswith(("x64: ", "arm64: ")) and devices.cpu_name() in name


def test_the_cpu_model_is_read_from_the_system():
    with open("/proc/cpuinfo") as f:
        models = {ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name")}
    assert not models or devices.cpu_name() in models
