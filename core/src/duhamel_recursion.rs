//! The exact O(1)-per-sample Duhamel recursion (work in progress).
