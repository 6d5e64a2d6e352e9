"""Files: run and sweep directories (each format's writer and reader together), the
recording view shared by exports and figures, measured data, and USD."""

PROBE_RECORDS = {
    "summary": "the probes the summary is measured from (a strip's laser and tip x; a sheet's clamp and markers)",
    "all": "every probe (the full record)",
    "none": "no probe series, the summary only",
}
"""What a sweep keeps of each variant's probe series (``warpcloth sweep --probes``; here,
where the command line reads it without the sweep directory's heavy imports)."""
