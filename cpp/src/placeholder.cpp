// keeps the static library non-empty until the first source lands
namespace revcol { int placeholder_symbol = 0; }
