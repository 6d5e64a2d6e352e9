"""Registers, stack and spills per CUDA kernel, compiled ahead of time, and the occupancy
they imply (run by hand; no GPU needed).

    python benchmarks/cuda_registers.py [--archs 80 90] [--cuobjdump PATH] [--ptxas PATH]

Every kernel variant (precision × scheme × bending law, the set tests/test_cuda_build.py
compiles) is compiled by Warp's NVRTC to CUBIN, the binary Warp loads on an sm_80 or sm_90
device, and to PTX. Registers per thread, stack frame and local memory are read from the
CUBINs with ``cuobjdump -res-usage``; spill stores and loads need ``ptxas -v``, run on the
PTX for the same architecture (its register count is checked against the CUBIN's). The
tools are looked for on PATH and in NVIDIA's pip packages: ``pip install
nvidia-cuda-cuobjdump`` (cuobjdump) and ``nvidia-cuda-nvcc`` (ptxas); neither is a project
dependency, and a column whose tool is missing prints "-".

The occupancy table takes each ``advance`` kernel's registers (one thread per strip, or per
sheet for ``sheet.advance``) to an A100 (sm_80, 108 SMs) and an H100/H200 (sm_90, 132
SMs): 65 536 registers and 64 resident warps per SM, registers allocated per warp in
units of 256, at most 32 blocks per SM (NVIDIA's occupancy calculator rules). For B =
1e3, 1e4, 1e5 strips (or sheets) it prints how many blocks the launch has, how many SMs
they can occupy, the waves, and the resident warps as a share of the GPU's warp slots,
for Warp's default 256 threads a block and for 64. An estimate from the rules, not a
measurement: benchmarks/gpu.py measures.
"""

from __future__ import annotations

import argparse
import logging
import math
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

import warp as wp
from warpcloth.kernels import build_strip, hinge_kernels, laws, sheet

from warpcloth.strip import PRECISIONS, SOLVERS


def variants() -> dict[str, wp.Kernel]:
    """Every kernel the project can load, by ``name-precision[-scheme]`` (as tests/test_cuda_build.py)."""
    out = {}
    for precision, scalar in PRECISIONS.items():
        for scheme in SOLVERS:
            out[f"advance-{precision}-{scheme}"] = build_strip(scalar, scheme).advance
        out[f"initialise_hinges-{precision}"] = hinge_kernels(scalar).initialise_hinges
        out[f"moment_along_path-{precision}"] = laws.build(scalar).moment_along_path
        out[f"sheet.advance-{precision}"] = sheet.build(scalar).advance
    return out


def find_tool(name: str, given: str | None) -> str | None:
    """``given``, else ``name`` on PATH, else in an NVIDIA pip package (nvidia/cu*/bin)."""
    if given:
        return given
    found = shutil.which(name)
    if found:
        return found
    try:
        import nvidia  # namespace package of NVIDIA's CUDA wheels
    except ImportError:
        return None
    for root in nvidia.__path__:
        for candidate in sorted(Path(root).glob(f"*/bin/{name}")):
            return str(candidate)
    return None


def ptxas_release(tool: str) -> tuple[int, int]:
    """The CUDA release of ``tool`` (``ptxas --version``), (0, 0) if it does not say."""
    text = subprocess.run([tool, "--version"], capture_output=True, text=True).stdout
    match = re.search(r"release (\d+)\.(\d+)", text)
    return (int(match[1]), int(match[2])) if match else (0, 0)


def cuobjdump_usage(tool: str, cubin: Path) -> dict[str, dict[str, int]]:
    """``{function: {"REG": …, "STACK": …, "LOCAL": …, …}}`` from ``cuobjdump -res-usage``."""
    text = subprocess.run([tool, "-res-usage", str(cubin)], check=True, capture_output=True, text=True).stdout
    usage, function = {}, None
    for line in text.splitlines():
        match = re.match(r"\s*Function (\S+):", line)
        if match:
            function = match.group(1)
        elif function and "REG:" in line:
            usage[function] = {key: int(value) for key, value in re.findall(r"(\w+(?:\[\d+\])?):(\d+)", line)}
            function = None
    return usage


def ptxas_usage(tool: str, ptx: Path, arch: int, scratch: Path) -> dict[str, dict[str, int]]:
    """``{entry: {"registers", "stack", "spill_stores", "spill_loads"}}`` from ``ptxas -v``."""
    clean = scratch / f"{ptx.stem}.ptx"
    clean.write_bytes(ptx.read_bytes().rstrip(b"\0"))  # Warp writes the C string's terminating NUL
    result = subprocess.run(
        [tool, "-v", f"-arch=sm_{arch}", "-O3", str(clean), "-o", str(scratch / "out.cubin")],
        check=True,
        capture_output=True,
        text=True,
    )
    usage, function, entry = {}, None, None
    for line in (result.stdout + result.stderr).splitlines():
        if match := re.search(r"Compiling entry function '(\S+)'", line):
            entry = match.group(1)
            usage[entry] = {}
        elif match := re.search(r"Function properties for (\S+)", line):
            function = match.group(1)
        elif function in usage and (
            match := re.search(r"(\d+) bytes stack frame, (\d+) bytes spill stores, (\d+) bytes spill loads", line)
        ):
            usage[function].update(stack=int(match[1]), spill_stores=int(match[2]), spill_loads=int(match[3]))
        elif entry and (match := re.search(r"Used (\d+) registers", line)):
            usage[entry]["registers"] = int(match[1])
            entry = None
    return usage


SMS = {80: ("A100", 108), 90: ("H100/H200", 132)}
REGISTERS_PER_SM, WARP_SLOTS, MAX_BLOCKS, ALLOCATION_UNIT = 65536, 64, 32, 256
BATCHES = (1000, 10000, 100000)


def blocks_per_sm(registers: int, block_dim: int) -> int:
    """Resident blocks of ``block_dim`` threads per SM at ``registers`` per thread."""
    warps = math.ceil(block_dim / 32)
    per_warp = math.ceil(registers * 32 / ALLOCATION_UNIT) * ALLOCATION_UNIT
    return min(MAX_BLOCKS, WARP_SLOTS // warps, REGISTERS_PER_SM // (per_warp * warps))


def occupancy_rows(name: str, arch: int, registers: int) -> list[str]:
    """Table rows: the launch of B strips at 256 and 64 threads a block."""
    gpu, sms = SMS[arch]
    rows = []
    for block_dim in (256, 64):
        resident = blocks_per_sm(registers, block_dim)
        for b in BATCHES:
            blocks = math.ceil(b / block_dim)
            busy = min(sms, blocks)
            warps = min(math.ceil(b / 32), resident * sms * math.ceil(block_dim / 32))
            rows.append(
                f"| {name:<30} | {gpu:<9} | {registers:>4} | {block_dim:>5} | {resident:>10} | {b:>6} | "
                f"{blocks:>6} | {busy:>4}/{sms} | {blocks / (resident * sms):5.2f} | "
                f"{warps / (sms * WARP_SLOTS):10.1%} |"
            )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--archs", type=int, nargs="+", default=[80, 90])
    parser.add_argument("--cuobjdump", help="path of cuobjdump (default: PATH, then NVIDIA's pip packages)")
    parser.add_argument("--ptxas", help="path of ptxas (default: PATH, then NVIDIA's pip packages)")
    args = parser.parse_args()
    wp.config.log_level = logging.WARNING
    wp.config.quiet = True
    wp.init()
    cuobjdump, ptxas = find_tool("cuobjdump", args.cuobjdump), find_tool("ptxas", args.ptxas)
    nvrtc = wp._src.context.runtime.toolkit_version
    if ptxas and ptxas_release(ptxas) < nvrtc:
        # An older ptxas rejects the PTX ISA of a newer NVRTC (".version 9.4" from CUDA 13.4).
        print(
            f"not using {ptxas}: CUDA {'.'.join(map(str, ptxas_release(ptxas)))} is older than Warp's NVRTC "
            f"(CUDA {'.'.join(map(str, nvrtc))}); pip install nvidia-cuda-nvcc or pass --ptxas"
        )
        ptxas = None
    if not cuobjdump and not ptxas:
        raise SystemExit(
            "neither cuobjdump nor ptxas found: pip install nvidia-cuda-cuobjdump (and "
            "nvidia-cuda-nvcc for spill counts), or pass --cuobjdump / --ptxas"
        )
    print(
        f"warp {wp.__version__}, NVRTC of CUDA {'.'.join(map(str, nvrtc))}; "
        f"cuobjdump: {cuobjdump or '-'}; ptxas: {ptxas or '-'}"
    )
    print("registers per thread; stack, local and spills in bytes per thread")
    header = (
        f"| {'kernel':<42} | {'arch':<5} | {'registers':>9} | {'stack':>5} | {'local':>5} | "
        f"{'spill stores':>12} | {'spill loads':>11} |"
    )
    print(header)
    print("|" + "|".join("-" * len(cell) for cell in header.split("|")[1:-1]) + "|")
    occupancy = []
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        for name, kernel in variants().items():
            cubins = wp.compile_aot_module(kernel.module, arch=args.archs, module_dir=folder, use_ptx=False)
            ptxs = (
                wp.compile_aot_module(kernel.module, arch=args.archs, module_dir=folder, use_ptx=True)
                if ptxas
                else [None] * len(args.archs)
            )
            entry = f"{kernel.get_mangled_name()}_cuda_kernel_forward"
            for arch, cubin, ptx in zip(args.archs, cubins, ptxs, strict=True):
                binary = cuobjdump_usage(cuobjdump, cubin)[entry] if cuobjdump else {}
                assembled = ptxas_usage(ptxas, ptx, arch, folder)[entry] if ptxas else {}
                registers = binary.get("REG", assembled.get("registers"))
                if binary and assembled and binary["REG"] != assembled["registers"]:
                    registers = f"{binary['REG']} ({assembled['registers']})"  # ptxas differs from NVRTC

                def cell(value: object, width: int) -> str:
                    return f"{'-' if value is None else value:>{width}}"

                print(
                    f"| {name:<42} | sm_{arch:<2} | {cell(registers, 9)} | "
                    f"{cell(binary.get('STACK', assembled.get('stack')), 5)} | {cell(binary.get('LOCAL'), 5)} | "
                    f"{cell(assembled.get('spill_stores'), 12)} | {cell(assembled.get('spill_loads'), 11)} |"
                )
                count = binary.get("REG", assembled.get("registers"))
                if name.split("-")[0] in ("advance", "sheet.advance") and arch in SMS and count is not None:
                    occupancy += occupancy_rows(name, arch, count)
    print("\noccupancy of the strip and sheet kernels (one thread per strip or sheet), from the registers above")
    print(
        f"| {'kernel':<30} | {'GPU':<9} | {'regs':>4} | {'block':>5} | {'blocks/SM':>10} | {'B':>6} | "
        f"{'blocks':>6} | {'SMs busy':>8} | {'waves':>5} | {'warp slots':>10} |"
    )
    print("|" + "|".join(["---"] * 10) + "|")
    for row in occupancy:
        print(row)


if __name__ == "__main__":
    main()
