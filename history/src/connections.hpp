#pragma once
// The backends' constructors (one file each), for database.cpp's connect().
#include <memory>
#include <string>

#include "tunekit/history/database.hpp"

namespace tunekit::history {
std::unique_ptr<Connection> connect_sqlite(const std::string& path);
std::unique_ptr<Connection> connect_postgresql(const std::string& url);
}  // namespace tunekit::history
