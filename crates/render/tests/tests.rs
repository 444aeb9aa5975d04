//! Integration tests of `render` (one test binary, topic modules).

mod module_graph;
