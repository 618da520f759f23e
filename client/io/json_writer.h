#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace tetrefine::io {

// A minimal pretty-printing JSON writer (the CLI's statistics file, the reproduction's results),
// with commas, nesting and string escaping handled so the output always parses. Doubles are written
// in their shortest round-trip form (they read back to the same bits); NaN and infinities, which
// JSON cannot express, are written as null.
class JsonWriter {
 public:
  void BeginObject();
  void EndObject();
  void BeginArray();
  void EndArray();
  // The key of the next value inside an object.
  void Key(std::string_view key);

  void String(std::string_view value);
  void Number(double value);
  void Int(int64_t value);
  void Bool(bool value);
  void Null();

  // Shorthands for a key and its value.
  template <typename T>
  void Field(std::string_view key, const T& value) {
    Key(key);
    Value(value);
  }

  // The document, with a final newline. Only once every object and array is closed.
  std::string Take();

 private:
  void Value(std::string_view v) { String(v); }
  void Value(const char* v) { String(v); }
  void Value(const std::string& v) { String(v); }
  void Value(double v) { Number(v); }
  void Value(int64_t v) { Int(v); }
  void Value(int v) { Int(v); }
  void Value(bool v) { Bool(v); }
  void BeforeValue();
  void Newline();
  void Close(char bracket);

  std::string out_;
  // Per open container: true once it holds an element (the next one needs a comma).
  std::vector<bool> has_element_;
  bool after_key_ = false;
};

// `text` as a quoted JSON string.
std::string JsonQuote(std::string_view text);

}  // namespace tetrefine::io
