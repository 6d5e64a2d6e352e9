"""Files: run and sweep directories (each format's writer and reader together), the
recording view shared by exports and figures, measured data, and USD."""
