"""Scene files bundled with warpcloth (``warpcloth run damped_swing`` finds them here)."""
