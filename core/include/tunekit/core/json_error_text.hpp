#pragma once
// What a JSON library error (nlohmann::json's exception text) says, in plain words for a
// user's message: "[json.exception.type_error.302] type must be number, but is string"
// becomes "a number was expected, but found text". Takes the text (what()) so that core
// needs no JSON library.

#include <string>
#include <string_view>

namespace tunekit::core {

/// The plain-words form of a nlohmann::json exception's what(): the library's tag
/// ("[json.exception.KIND.ID] ") removed and its known wordings rephrased; other text
/// passes through without the tag.
std::string plain_json_error(std::string_view what);

/// The one-line form of a std::filesystem::filesystem_error's what() for a user's message:
/// "filesystem error: cannot create directories: Permission denied [ro/run]" becomes
/// "ro/run: cannot create directories: Permission denied" (libstdc++'s wording).
std::string plain_filesystem_error(std::string_view what);

}  // namespace tunekit::core
