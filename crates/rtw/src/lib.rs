//! Not yet implemented: see the open issue for this crate.
#![cfg_attr(not(feature = "std"), no_std)]
