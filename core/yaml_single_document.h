#ifndef DALA_CORE_YAML_SINGLE_DOCUMENT_H_
#define DALA_CORE_YAML_SINGLE_DOCUMENT_H_

// A guard in front of cv::FileStorage's YAML parser (OpenCV 4.6, Debian 12).
//
// OpenCV's parser reads a stream of documents. Once the first document's root collection ends
// before the end of the text (a line indented less than the root, or a "..." marker), it skips
// three characters and looks for the next "---". If it then meets a '-' that does not start
// "---", it loops forever without advancing: the 9-byte text " L:0\n-:\n-" hangs every reader
// (found by tests/fuzz/bench_suite_fuzzer).
// dala's files are single documents, so the guard refuses any text that goes on after the first
// document's root ends, naming the line, before OpenCV sees it.

#include <string>

namespace dala {

// Throws dala::Error "<name>: line N: ..." when `yaml` holds content after the end of its first
// document's root collection (where OpenCV would start a second document). A leading "%YAML"
// directive, a leading "---", blank lines and comment lines are allowed anywhere.
void CheckSingleYamlDocument(const std::string& yaml, const std::string& name);

}  // namespace dala

#endif  // DALA_CORE_YAML_SINGLE_DOCUMENT_H_
