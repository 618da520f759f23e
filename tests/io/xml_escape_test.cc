// EscapeXml: whatever a user names an array or a file, an XML parser reads back the same text.

#include "client/io/xml_escape.h"

#include <random>
#include <string>

#include "gtest/gtest.h"
#include "pugixml.hpp"

namespace tetrefine::io {
namespace {

TEST(IoXmlEscape, EveryMarkupCharacterBecomesAnEntity) {
  EXPECT_EQ(EscapeXml("a&b<c>d\"e'f"), "a&amp;b&lt;c&gt;d&quot;e'f");
  EXPECT_EQ(EscapeXml(""), "");
}

TEST(IoXmlEscape, AnAttributeReadsBackAsTheOriginalText) {
  const std::string alphabet = "ab &<>\"'=/;#xX0";
  for (uint32_t seed = 0; seed < 200; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<size_t> pick(0, alphabet.size() - 1);
    std::string text(seed % 24, ' ');
    for (char& c : text) c = alphabet[pick(rng)];
    const std::string xml = "<A Name=\"" + EscapeXml(text) + "\">" + EscapeXml(text) + "</A>";
    pugi::xml_document doc;
    ASSERT_TRUE(doc.load_string(xml.c_str(), pugi::parse_default | pugi::parse_ws_pcdata))
        << "seed " << seed << ": " << xml;
    EXPECT_EQ(doc.child("A").attribute("Name").value(), text) << "seed " << seed;
    EXPECT_EQ(doc.child("A").text().get(), text) << "seed " << seed;
  }
}

}  // namespace
}  // namespace tetrefine::io
