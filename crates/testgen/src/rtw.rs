//! Generators and checks for `shadowmap-rtw` (fuzz targets and property tests).
