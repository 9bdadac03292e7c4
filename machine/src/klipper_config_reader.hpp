#pragma once
// Reads a Klipper printer.cfg as Klipper loads it (Kevin O'Connor et al., Klipper 3D printer
// firmware, klippy/configfile.py ConfigFileReader and ConfigAutoSave, 2016-2026):
//  - an INI dialect (Python's configparser, strict=False): `[section]` headers at column 0,
//    `key: value` or `key = value` options (keys in lower case), indented continuation lines;
//    everything from the first '#' of a line is a comment, and ';' after a blank;
//  - `[include SPEC]` reads the files SPEC names (a glob relative to the including file's folder,
//    sorted) where it stands; a missing file that is no glob is an error, and so is an include
//    loop ("Recursive include of config file");
//  - a later option overrides an earlier one, also across files;
//  - the SAVE_CONFIG block at the end of the main file (its header line, then "#*# " lines) is
//    read last, but an option of the block that the regular part also sets is dropped
//    (ConfigAutoSave._strip_duplicates): SAVE_CONFIG comments the regular one out when it saves.

#include <cstddef>
#include <map>
#include <string>

#include "profile_import_detail.hpp"

namespace tunekit::machine::detail {

struct KlipperOption {
  std::string value;  ///< as written, without comments (a multi-line value's first line)
  Site site;
};

struct KlipperSection {
  std::map<std::string, KlipperOption> options;  ///< by lower-case key
  Site site;                                     ///< the first header of the section
  /// The option, or nullptr.
  const KlipperOption* find(const std::string& key) const;
};

struct KlipperConfig {
  std::map<std::string, KlipperSection> sections;  ///< by name as written, "stepper_x", "adxl345 toolhead"
  std::string main_file;
  /// The section, or nullptr.
  const KlipperSection* find(const std::string& name) const;
};

/// Reads `path` with its includes and SAVE_CONFIG block. InputError (exit 2) located FILE:LINE
/// for a line that is neither a section, an option nor a comment, an option before any section,
/// a missing include or an include loop, more than 64 nested includes or 1000 files.
KlipperConfig read_klipper_config(const std::string& path);

}  // namespace tunekit::machine::detail
