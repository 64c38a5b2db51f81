// The one source of the targets that compile the tests' precompiled headers
// (tests/CMakeLists.txt); it has nothing of its own.
