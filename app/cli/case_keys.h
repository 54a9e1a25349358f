// The case-key reference (`demdesign keys`, docs/case-keys.md), written from the readers
// themselves: every shipped case, material file and measurement file is read with a KeyRecorder
// set (src/case/yaml_check.h), every equipment generator also once with no parameters (its
// defaults), and each key the readers asked for becomes a row: type, unit, default, valid range
// and an example from a shipped file. A key added to a reader appears here without anyone
// writing it.
#pragma once

#include <string>

namespace dem::app {

/// The reference as Markdown (`markdown`, what docs/case-keys.md holds) or plain text, from the
/// files under `source_dir` (the source tree: cases/, materials/, tests/data/cross_engine/).
/// Throws CaseError when a shipped file cannot be read.
std::string case_key_reference(const std::string& source_dir, bool markdown);

/// The source tree this program was built from (the parent of the shipped material library).
std::string default_source_dir();

}  // namespace dem::app
