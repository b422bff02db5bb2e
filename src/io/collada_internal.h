#pragma once
// Shared parts of the COLLADA reader (collada.cpp: scene graph, materials, lights, cameras;
// collada_mesh.cpp: geometry). Not a public interface.
#include "candela/io/collada.h"
#include "candela/util/error.h"

#include <tinyxml2.h>

#include <set>
#include <string>
#include <unordered_map>
#include <vector>

namespace candela::collada_detail {

using tinyxml2::XMLElement;

/// Parsing context: the file name for messages, the id table and the diagnostics sink.
class Context {
  public:
    Context(const std::string& display_name, Diagnostics& diag)
        : name_(display_name), diag_(diag) {}

    const std::string& name() const { return name_; }
    Diagnostics& diag() { return diag_; }

    /// Throws Error(Scene) at element `e` (its line; the file alone when `e` is null).
    [[noreturn]] void fail(const XMLElement* e, const std::string& what) const;
    /// Records `file:line: warning: what` (an error in strict mode).
    void warn(const XMLElement* e, const std::string& what);
    /// Warns once per `kind` for the whole file (ignored-element warnings).
    void warn_once(const std::string& kind, const XMLElement* e, const std::string& what);
    void note(const XMLElement* e, const std::string& what);

    /// Fills the id table with every element that has an `id` (later duplicates win).
    void index_ids(XMLElement* root);
    /// The element a `#id` reference names, or null. A reference without `#` is taken as an id.
    XMLElement* lookup(const char* ref) const;
    /// Like lookup(), but a missing or dangling reference is an error naming `attr` on `e`.
    XMLElement* resolve(const XMLElement* e, const char* attr, const char* expected_tag) const;

    // ---- numbers ---------------------------------------------------------------------------
    /// Parses all whitespace-separated numbers in `e`'s text into `out` (cleared first).
    /// Non-numeric text and non-finite values (nan, inf, out of range) are errors; `what`
    /// names the element in messages.
    void parse_floats(const XMLElement* e, std::vector<float>& out, const std::string& what) const;
    void parse_doubles(const XMLElement* e, std::vector<double>& out,
                       const std::string& what) const;
    /// Non-negative integers (indices and counts).
    void parse_uints(const XMLElement* e, std::vector<std::uint32_t>& out,
                     const std::string& what) const;
    /// Exactly `n` floats from `e`'s text.
    void parse_exact(const XMLElement* e, float* out, std::size_t n, const std::string& what) const;
    /// An upper bound on how many whitespace-separated numbers `e`'s text can hold (each needs
    /// a character and all but the last a separator), computed without parsing. Used to reject
    /// size claims (`count` attributes, vcount sums) before anything is allocated for them.
    static std::size_t max_numbers_in(const XMLElement* e);
    /// A required non-negative integer attribute.
    std::uint32_t uint_attr(const XMLElement* e, const char* attr, bool required,
                            std::uint32_t fallback) const;

  private:
    std::string name_;
    Diagnostics& diag_;
    std::unordered_map<std::string, XMLElement*> ids_;
    std::set<std::string> warned_kinds_;
};

/// "name" attribute, else "id", else the tag name.
std::string display_id(const XMLElement* e);

/// Parses a `<geometry>` (mesh or CGL sphere) into `out`. Returns false (after one warning)
/// for geometry kinds candela ignores.
bool parse_geometry(Context& ctx, const XMLElement* geometry, DescGeometry& out);

} // namespace candela::collada_detail
