"""Camera calibration with a ChArUco board (issue 14): one stage per module.

`board` finds the board on a photo (a `BoardView`), `fit` fits the pinhole and distortion with
their covariance, `quality` measures coverage, tilts and the distortion's uncertainty, `report`
judges the set against `CalibrationRules` and builds the `CalibrationReport`; `lens` is the
camera model they share, `photos` reads PNG and JPEG files within limits, `printing` draws the
printable board, `cli` holds `lumipose calibrate`. docs/calibration.md tells the whole story.
"""
