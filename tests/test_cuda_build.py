"""The CUDA build, checked on machines without a GPU: every kernel compiles for sm_80 and sm_90.

CI has no GPU, so test_gpu.py is skipped there and every other test runs the kernels
through Warp's CPU backend (clang). Code that clang accepts but NVRTC rejects (a
construct, an intrinsic or an overload of one precision that only the CUDA headers lack,
anything under ``__CUDA_ARCH__``) would otherwise be found only when someone runs on a
GPU. Warp ships NVRTC inside its own library and compiles ahead of time without a driver
(``wp.compile_aot_module(module, arch=...)``), so this test does the CUDA build here.

Every kernel is a Warp module of its own (``module="unique"``), generated per precision
and integrator scheme (every bending law is in each: kernels/laws.py), the woven sheet's
three (kernels/sheet.py) per precision; :data:`VARIANTS`
builds each from the registries the project uses (``PRECISIONS``, ``SOLVERS``), and
:func:`test_every_kernel_is_built_here` reads kernels/ and warpcloth/ for ``@wp.kernel``
so a new kernel cannot be left out. Each compiles to CUBIN, what Warp loads on an sm_80 or
sm_90 device (each kernel's float64 build for sm_90 and its float32 build for sm_80, so every
source passes both architectures' back ends): NVRTC's front end, PTX generation and ptxas, about 8 s for all of them on
two cores, into a fresh folder each run (no kernel cache to hide a failure). The binary is
read back: a CUDA ELF for the requested architecture holding the kernel's entry point.
:func:`test_a_cuda_only_error_fails_the_build` shows that a kernel the CPU runs but CUDA
cannot compile fails this check. Skipped only where Warp has no NVRTC for these targets
(e.g. macOS wheels).
"""

import ast
from pathlib import Path

import pytest
import warp as wp
from conftest import kernel_variants

from warpcloth.strip import PRECISIONS

ROOT = Path(__file__).resolve().parents[1]
ARCHS = (80, 90)  # Ampere (A100) and Hopper (H100, H200)
EM_CUDA = 190  # ELF e_machine of a CUBIN


VARIANTS = kernel_variants()


def _nvrtc_missing() -> str:
    if not hasattr(wp, "compile_aot_module"):
        return f"Warp {wp.__version__} has no wp.compile_aot_module"
    missing = sorted(set(ARCHS) - set(wp.get_cuda_supported_archs()))
    if missing:
        return f"Warp {wp.__version__} has no NVRTC for sm_{', sm_'.join(map(str, missing))} on this platform"
    return ""


NVRTC_MISSING = _nvrtc_missing()
needs_nvrtc = pytest.mark.skipif(bool(NVRTC_MISSING), reason=NVRTC_MISSING or "NVRTC available")


def cubin_arch(binary: bytes) -> int:
    """The SM architecture a CUBIN was built for (asserting it is a 64-bit CUDA ELF)."""
    assert binary[:4] == b"\x7fELF", "not an ELF file"
    assert binary[4] == 2, "not a 64-bit ELF"
    assert int.from_bytes(binary[18:20], "little") == EM_CUDA, "not a CUDA ELF"
    flags = int.from_bytes(binary[48:52], "little")
    # ELF ABI version 8 (CUDA 12.8 on) moved the SM number from bits 0-7 to bits 8-15.
    return (flags >> 8) & 0xFF if binary[8] >= 8 else flags & 0xFF


def compile_cuda(kernel: wp.Kernel, folder: Path, archs: tuple[int, ...] = ARCHS) -> list[Path]:
    return wp.compile_aot_module(kernel.module, arch=list(archs), module_dir=folder, use_ptx=False)


def test_every_kernel_is_built_here():
    # Every function decorated @wp.kernel in the project's sources is among VARIANTS, in
    # every precision, and each variant is a module of its own (distinct code).
    declared = set()
    for folder in (ROOT / "kernels", ROOT / "warpcloth"):
        for path in folder.rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.FunctionDef):
                    for decorator in node.decorator_list:
                        target = decorator.func if isinstance(decorator, ast.Call) else decorator
                        if ast.unparse(target) == "wp.kernel":
                            declared.add(node.name)
    assert declared, "found no @wp.kernel in kernels/ or warpcloth/"
    built = {kernel.func.__name__ for kernel in VARIANTS.values()}
    assert declared == built, f"kernels not compiled by this test: {sorted(declared - built)}"
    for precision in PRECISIONS:
        assert {k.func.__name__ for name, k in VARIANTS.items() if f"-{precision}" in name} == declared
    assert len({id(kernel.module) for kernel in VARIANTS.values()}) == len(VARIANTS)


@needs_nvrtc
@pytest.mark.parametrize(
    "name",
    # the sheet's fused advance takes NVRTC 6-9 s and its force pass with the clamp's ghosts
    # 3.5-4.7 s: CI compiles them, the inner loop does not
    [
        pytest.param(n, marks=pytest.mark.slow) if n.startswith(("sheet.advance", "sheet.internal_forces")) else n
        for n in sorted(VARIANTS)
    ],
)
def test_kernel_compiles_for_cuda(name, tmp_path):
    # each kernel's float64 build for sm_90 and its float32 build for sm_80: the same source
    # through both architectures' back ends, at half the compiling of both for each
    kernel = VARIANTS[name]
    archs = (90,) if "-float64" in name else (80,)
    paths = compile_cuda(kernel, tmp_path, archs)
    assert len(paths) == len(archs)
    entry = f"{kernel.get_mangled_name()}_cuda_kernel_forward".encode()
    for arch, path in zip(archs, paths, strict=True):
        assert path.suffix == ".cubin" and path.is_file(), path
        binary = path.read_bytes()
        assert binary, f"{path.name} is empty"
        assert cubin_arch(binary) == arch, path.name
        assert entry in binary, f"{path.name} lacks the entry point {entry.decode()}"
        assert b"_cuda_kernel_backward" not in binary, f"{path.name} carries adjoint code"


# The negative control: valid C++ everywhere except in device code for sm_90 and newer.
_SM90_ONLY_ERROR = """
#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ >= 900
    return x + undeclared_on_sm90;
#else
    return x + 1.0;
#endif
"""


@wp.func_native(_SM90_ONLY_ERROR)
def _bump(x: wp.float64) -> wp.float64: ...


@wp.kernel(module="unique", enable_backward=False)
def _broken_on_sm90(values: wp.array(dtype=wp.float64)):
    i = wp.tid()
    values[i] = _bump(values[i])


@needs_nvrtc
def test_a_cuda_only_error_fails_the_build(tmp_path):
    values = wp.zeros(2, dtype=wp.float64, device="cpu")
    wp.launch(_broken_on_sm90, dim=2, inputs=[values], device="cpu")
    assert values.numpy().tolist() == [1.0, 1.0]  # the CPU build, all other tests see, is fine
    module = _broken_on_sm90.module
    (sm80,) = wp.compile_aot_module(module, arch=80, module_dir=tmp_path / "sm80", use_ptx=False)
    assert cubin_arch(sm80.read_bytes()) == 80
    with pytest.raises(Exception, match="CUDA kernel build failed"):
        wp.compile_aot_module(module, arch=90, module_dir=tmp_path / "sm90", use_ptx=False)
