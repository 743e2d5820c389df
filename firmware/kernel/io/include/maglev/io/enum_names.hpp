// One table per enum: an X-macro list `LIST(X)` of X(enumerator, value,
// "name") generates both the enum (explicit values: these cross a wire or a
// register, so never renumber, only append) and its to_string().
//
//   #define MAGLEV_FRUITS(X) X(kApple, 0, "apple") X(kPear, 1, "pear")
//   enum class Fruit : std::uint8_t { MAGLEV_FRUITS(MAGLEV_ENUMERATOR) };
//   MAGLEV_ENUM_TO_STRING(Fruit, MAGLEV_FRUITS)   // in the .cpp: "?" for other values
#pragma once

#define MAGLEV_ENUMERATOR(name, value, text) name = value,
#define MAGLEV_ENUM_NAME_CASE(name, value, text) \
  case E::name:                                  \
    return text;
#define MAGLEV_ENUM_TO_STRING(Enum, LIST) \
  const char* to_string(Enum v) {         \
    using E = Enum;                       \
    switch (v) { LIST(MAGLEV_ENUM_NAME_CASE) } \
    return "?";                           \
  }
