# Writes OUT, a C++ source holding the text of the documents CASE and FORCE
# (run by the custom command in ../CMakeLists.txt at build time).
file(READ "${CASE}" case_text)
file(READ "${FORCE}" force_text)
file(WRITE "${OUT}.tmp"
"// Generated from ${CASE} and ${FORCE}: do not edit.\n"
"#include <string_view>\n"
"namespace smc::machining::detail {\n"
"extern const std::string_view kPaperCaseText;\n"
"extern const std::string_view kPaperForceModelText;\n"
"const std::string_view kPaperCaseText = R\"smc_embed(${case_text})smc_embed\";\n"
"const std::string_view kPaperForceModelText = R\"smc_embed(${force_text})smc_embed\";\n"
"}  // namespace smc::machining::detail\n")
file(COPY_FILE "${OUT}.tmp" "${OUT}" ONLY_IF_DIFFERENT)
file(REMOVE "${OUT}.tmp")
