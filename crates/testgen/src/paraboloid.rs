//! Generators and checks for `shadowmap-paraboloid` (fuzz targets and property tests).
