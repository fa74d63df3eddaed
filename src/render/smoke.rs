//! Smoke pass: a tiny compute dispatch that proves the device works.
