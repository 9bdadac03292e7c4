// Anchor translation unit for the test areas' shared precompiled header (tests/CMakeLists.txt).
namespace tunekit::test {
int pch_anchor() { return 0; }
}  // namespace tunekit::test
