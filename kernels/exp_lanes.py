"""Several exponentials in one call on the CPU: glibc's vector math library (libmvec).

The paper's law takes one exponential per hinge and substep (kernels/bending_tagawa2003.py),
and Warp's CPU backend calls glibc's scalar ``exp`` for each: about a fifth of a swinging
strip's step (benchmarks/RESULTS.md, 2026-12-07). libmvec evaluates 4 float64
exponentials in one AVX2 call (``_ZGVdN4v_exp``), or 8 in an AVX-512 one
(``_ZGVeN8v_exp``), for about the time of one scalar call, so the strip's force pass
(kernels/forces.py) follows its hinges in groups of :func:`lane_width` and takes the
group's exponentials together.

libmvec promises 4 ulp, where glibc's scalar ``exp`` rounds within 1; the two differ on
about half of all arguments (``benchmarks/cpu_lanes.py``), so a strip's frames move by
rounding, ~1e-12 of their size over a 4 s hysteretic swing (tests/test_exp_lanes.py
states and checks the tolerance). ``WARPCLOTH_EXP_LANES=1`` takes the scalar ``exp`` of
every hinge, bitwise the force pass of warpcloth before the groups (the golden outputs
are checked that way) and in the order of operations a GPU takes.

A GPU takes one hinge at a time (its ``exp`` is an instruction sequence, not a call), as
do float32, sheets and any CPU without libmvec or AVX2 and FMA: a width of 1. The width
is chosen here and the instruction set again when the kernel is compiled
(``__AVX512F__``, ``__AVX2__``), so a kernel built for a CPU without them falls back to
scalar calls rather than to a wrong calling convention.
"""

import ctypes
import functools
import os
import platform
from typing import Any

import warp as wp

from warpcloth.errors import EnvironmentSettingError, InternalError

ENVIRONMENT = "WARPCLOTH_EXP_LANES"
"""The environment variable that sets the width: ``auto`` (the default; also when empty), 1, 4 or 8."""

WIDTHS = (1, 4, 8)
"""The group widths the force pass can take: one hinge, one AVX2 call, one AVX-512 call."""


@functools.cache
def _cpu_flags() -> frozenset[str]:
    try:
        with open("/proc/cpuinfo", encoding="ascii", errors="replace") as info:
            for line in info:
                if line.startswith("flags"):
                    return frozenset(line.split(":", 1)[1].split())
    except OSError:
        pass
    return frozenset()


@functools.cache
def libmvec_loaded() -> bool:
    """Whether glibc's libmvec is loaded into the process's global symbol table, where
    the linker of Warp's CPU kernels finds it (loaded here on first call)."""
    if platform.system() != "Linux" or platform.machine() != "x86_64":
        return False
    try:
        ctypes.CDLL("libmvec.so.1", mode=ctypes.RTLD_GLOBAL)
    except OSError:
        return False
    return True


def vector_exp_available() -> bool:
    """Whether this CPU takes libmvec's 4-wide exp: libmvec loaded, AVX2 and FMA."""
    flags = _cpu_flags()
    return libmvec_loaded() and "avx2" in flags and "fma" in flags


def requested_width() -> int | None:
    """The width ``WARPCLOTH_EXP_LANES`` asks for (None: ``auto``, empty or unset); an
    EnvironmentSettingError naming the variable for any other value, or for 4 or 8 where
    libmvec cannot be loaded. Checked before a run starts, whatever its device or body."""
    asked = os.environ.get(ENVIRONMENT, "").strip()
    if asked in ("", "auto"):
        return None
    if asked not in {str(w) for w in WIDTHS}:
        choices = ", ".join(map(str, WIDTHS))
        raise EnvironmentSettingError(ENVIRONMENT, f"is {asked!r}; it must be auto or one of {choices}")
    width = int(asked)
    if width > 1 and not libmvec_loaded():
        raise EnvironmentSettingError(
            ENVIRONMENT, f"is {width}, but glibc's libmvec.so.1 cannot be loaded here (Linux x86-64 only)"
        )
    return width


def lane_width(scalar: Any, device_is_cpu: bool) -> int:
    """How many hinges the strip's force pass follows together on this device: 4 on a CPU
    with AVX2, FMA and libmvec, else 1 (a GPU, float32, another CPU);
    ``WARPCLOTH_EXP_LANES`` sets it on a CPU in float64. Groups of 8 (one AVX-512 call)
    took 7–9 % less time than hinges one at a time on the swing sweep, groups of 4 15 %
    (benchmarks/RESULTS.md, 2026-12-07): the shorter group keeps the force pass compact."""
    asked = requested_width()
    if not device_is_cpu or scalar is not wp.float64:
        return 1
    if asked is not None:
        return asked
    return 4 if vector_exp_available() else 1


@functools.cache
def build(scalar: Any, width: int) -> Any:
    """``exp_of_lanes(x) -> e^x`` on a vector of ``width`` values (one of :data:`WIDTHS`):
    libmvec's call for float64 at widths 4 and 8 where the compiler targets AVX2 or
    AVX-512, else ``wp.exp`` of each."""
    if width not in WIDTHS:
        raise InternalError(f"a group of {width} hinges; the force pass takes one of {WIDTHS}")
    lanes = wp.types.vector(width, dtype=scalar)
    if width == 1 or scalar is not wp.float64:

        @wp.func
        def exp_of_lanes(x: lanes):
            out = lanes()
            for k in range(wp.static(width)):
                out[k] = scalar(1.0)  # e^0 exactly, without a call (a law with nothing to decay)
                if x[k] != scalar(0.0):
                    out[k] = wp.exp(x[k])
            return out

        return exp_of_lanes
    if not libmvec_loaded():
        raise InternalError(f"a group of {width} hinges asked for where libmvec.so.1 cannot be loaded")
    # A vector-function call needs the vector registers the libmvec variant is written
    # for: without them (a kernel compiled without -march=native, or for another CPU) the
    # call would pass its argument in memory, so the fallback is the scalar loop.
    snippet = f"""
    wp::vec_t<{width}, double> out;
#if defined(__AVX512F__) && {width} == 8
    typedef double lanes8 __attribute__((vector_size(64)));
    lanes8 exp8(lanes8) __asm__("_ZGVeN8v_exp");
    lanes8 a;
    for (int k = 0; k < 8; ++k) a[k] = x.c[k];
    lanes8 r = exp8(a);
    for (int k = 0; k < 8; ++k) out.c[k] = r[k];
#elif defined(__AVX2__)
    typedef double lanes4 __attribute__((vector_size(32)));
    lanes4 exp4(lanes4) __asm__("_ZGVdN4v_exp");
    for (int g = 0; g < {width}; g += 4) {{
        lanes4 a;
        for (int k = 0; k < 4; ++k) a[k] = x.c[g + k];
        lanes4 r = exp4(a);
        for (int k = 0; k < 4; ++k) out.c[g + k] = r[k];
    }}
#else
    for (int k = 0; k < {width}; ++k) out.c[k] = wp::exp(x.c[k]);
#endif
    return out;
    """

    @wp.func_native(snippet)
    def exp_of_lanes(x: lanes) -> lanes: ...

    return exp_of_lanes
