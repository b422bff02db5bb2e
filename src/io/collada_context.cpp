// COLLADA reader: the parsing context (messages, id table) and the number parsers.
#include "collada_internal.h"

#include <charconv>
#include <cmath>
#include <limits>

namespace candela {

namespace collada_detail {

// ---- Context ---------------------------------------------------------------------------------

void Context::fail(const XMLElement* e, const std::string& what) const {
    throw Error(ErrorKind::Scene, SourceLoc{name_, e ? e->GetLineNum() : 0}, what);
}

void Context::warn(const XMLElement* e, const std::string& what) {
    diag_.warn(SourceLoc{name_, e ? e->GetLineNum() : 0}, what);
}

void Context::warn_once(const std::string& kind, const XMLElement* e, const std::string& what) {
    if (warned_kinds_.insert(kind).second) warn(e, what);
}

void Context::note(const XMLElement* e, const std::string& what) {
    diag_.note(SourceLoc{name_, e ? e->GetLineNum() : 0}, what);
}

void Context::index_ids(XMLElement* root) {
    // Iterative pre-order walk: later duplicates overwrite earlier ones (spec §1.1).
    std::vector<XMLElement*> stack{root};
    while (!stack.empty()) {
        XMLElement* e = stack.back();
        stack.pop_back();
        if (const char* id = e->Attribute("id")) ids_[id] = e;
        // Push children in reverse so that they are visited in document order.
        std::vector<XMLElement*> kids;
        for (XMLElement* c = e->FirstChildElement(); c; c = c->NextSiblingElement())
            kids.push_back(c);
        for (auto it = kids.rbegin(); it != kids.rend(); ++it)
            stack.push_back(*it);
    }
}

XMLElement* Context::lookup(const char* ref) const {
    if (!ref || !*ref) return nullptr;
    if (*ref == '#') ++ref;
    auto it = ids_.find(ref);
    return it == ids_.end() ? nullptr : it->second;
}

XMLElement* Context::resolve(const XMLElement* e, const char* attr,
                             const char* expected_tag) const {
    const char* ref = e->Attribute(attr);
    if (!ref || !*ref) fail(e, std::string("<") + e->Name() + "> has no '" + attr + "' attribute");
    XMLElement* target = lookup(ref);
    if (!target)
        fail(e, std::string("<") + e->Name() + " " + attr + "=\"" + ref +
                    "\"> names no element (dangling reference '" + ref + "')");
    if (expected_tag && std::string(target->Name()) != expected_tag)
        fail(e, std::string("<") + e->Name() + " " + attr + "=\"" + ref + "\"> names a <" +
                    target->Name() + ">, expected a <" + expected_tag + ">");
    return target;
}

namespace {

inline bool is_space(char c) {
    return c == ' ' || c == '\n' || c == '\t' || c == '\r';
}

std::string token_at(const char* p) {
    std::string t;
    while (*p && !is_space(*p) && t.size() < 24)
        t += *p++;
    return t;
}

/// Calls f(double) for each number in `text`; reports failures through ctx.fail.
template <typename F>
void for_each_number(const Context& ctx, const XMLElement* e, const std::string& what, F&& f) {
    const char* p = e->GetText();
    if (!p) return;
    while (true) {
        while (is_space(*p))
            ++p;
        if (!*p) break;
        const char* start = p;
        if (*p == '+') ++p; // from_chars does not take a leading '+'
        const char* end = p;
        while (*end && !is_space(*end))
            ++end;
        double v = 0.0;
        auto res = std::from_chars(p, end, v);
        if (res.ec == std::errc::result_out_of_range)
            ctx.fail(e, what + ": '" + token_at(start) + "' is out of range");
        if (res.ec != std::errc() || res.ptr != end)
            ctx.fail(e, what + ": '" + token_at(start) + "' is not a number");
        if (!std::isfinite(v)) ctx.fail(e, what + ": '" + token_at(start) + "' is not finite");
        f(v, start);
        p = end;
    }
}

} // namespace

void Context::parse_doubles(const XMLElement* e, std::vector<double>& out,
                            const std::string& what) const {
    out.clear();
    for_each_number(*this, e, what, [&](double v, const char*) { out.push_back(v); });
}

void Context::parse_floats(const XMLElement* e, std::vector<float>& out,
                           const std::string& what) const {
    out.clear();
    constexpr double kFloatMax = std::numeric_limits<float>::max();
    for_each_number(*this, e, what, [&](double v, const char* tok) {
        if (std::abs(v) > kFloatMax)
            fail(e, what + ": '" + token_at(tok) + "' is out of single-precision range");
        out.push_back(static_cast<float>(v));
    });
}

void Context::parse_uints(const XMLElement* e, std::vector<std::uint32_t>& out,
                          const std::string& what) const {
    out.clear();
    const char* p = e->GetText();
    if (!p) return;
    while (true) {
        while (is_space(*p))
            ++p;
        if (!*p) break;
        const char* start = p;
        std::uint64_t v = 0;
        bool any = false;
        while (*p >= '0' && *p <= '9') {
            v = v * 10 + static_cast<std::uint64_t>(*p - '0');
            if (v > std::numeric_limits<std::uint32_t>::max())
                fail(e, what + ": '" + token_at(start) + "' is out of range");
            ++p;
            any = true;
        }
        if (!any || (*p && !is_space(*p)))
            fail(e, what + ": '" + token_at(start) + "' is not a non-negative integer");
        out.push_back(static_cast<std::uint32_t>(v));
    }
}

void Context::parse_exact(const XMLElement* e, float* out, std::size_t n,
                          const std::string& what) const {
    std::vector<float> v;
    parse_floats(e, v, what);
    if (v.size() != n)
        fail(e, what + " needs " + std::to_string(n) + " number" + (n == 1 ? "" : "s") +
                    " but has " + std::to_string(v.size()));
    for (std::size_t i = 0; i < n; ++i)
        out[i] = v[i];
}

std::size_t Context::max_numbers_in(const XMLElement* e) {
    const char* p = e ? e->GetText() : nullptr;
    return p ? (std::char_traits<char>::length(p) + 1) / 2 : 0;
}

std::uint32_t Context::uint_attr(const XMLElement* e, const char* attr, bool required,
                                 std::uint32_t fallback) const {
    const char* s = e->Attribute(attr);
    if (!s) {
        if (required)
            fail(e, std::string("<") + e->Name() + "> is missing the '" + attr + "' attribute");
        return fallback;
    }
    std::uint32_t v = 0;
    auto res = std::from_chars(s, s + std::char_traits<char>::length(s), v);
    if (res.ec != std::errc() || *res.ptr != '\0')
        fail(e, std::string("<") + e->Name() + "> attribute " + attr + "=\"" + s +
                    "\" is not a non-negative integer");
    return v;
}

std::string display_id(const XMLElement* e) {
    if (const char* n = e->Attribute("name")) return n;
    if (const char* n = e->Attribute("id")) return n;
    return e->Name();
}

} // namespace collada_detail

} // namespace candela
