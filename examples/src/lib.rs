//! Examples of use of the omnimvs libraries. The programs are the package's `[[example]]`
//! targets in `rust/` (listed with their commands in `README.md`); this library is empty.
