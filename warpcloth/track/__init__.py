"""From lab video to tracked shapes: camera and plane calibration from board images
(:mod:`~warpcloth.track.calibration`), frames and their timestamps
(:mod:`~warpcloth.track.video`), subpixel markers with their identity
(:mod:`~warpcloth.track.markers`) or, without markers, the centreline
(:mod:`~warpcloth.track.centreline`), the overlay figure (:mod:`~warpcloth.track.overlay`),
and the synthetic camera the tracker is checked against (:mod:`~warpcloth.track.render`)."""
