//! Generators and checks for `shadowmap-frustum` (fuzz targets and property tests).
