// The translation unit whose product is a shared precompiled header (cmake/SharedPrecompiledHeaders.cmake).
