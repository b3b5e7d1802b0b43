//! Generators and checks for `shadowmap-warp` (fuzz targets and property tests).
