"""What every body shares (docs/architecture.md): the one runner loop
(:func:`~warpcloth.core.runner.simulate_batch`), the solver contract and its fused base
(:mod:`.solver`), the divergence policy (:mod:`.divergence`), the output schedule
(:mod:`.schedule`), the result (:class:`~warpcloth.core.result.RunResult`) and the
resource checks. The strip (:mod:`warpcloth.strip`) and the woven sheet
(:mod:`warpcloth.sheet`) are sibling bodies on it; :mod:`warpcloth.bodies` is their registry.
"""
