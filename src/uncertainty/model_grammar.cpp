#include "uncertainty/model_grammar.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <initializer_list>
#include <iterator>
#include <stdexcept>
#include <utility>

namespace metro {
namespace internal {
namespace {

using Unary = double (*)(double);

struct FunctionInfo {
  const char* name;
  ModelFunction function;
  int arity;    // -1: one or more.
  Unary apply;  // The double function for the one-argument ones.
};

constexpr FunctionInfo kFunctions[] = {
    {"sin", ModelFunction::kSin, 1, [](double x) { return std::sin(x); }},
    {"cos", ModelFunction::kCos, 1, [](double x) { return std::cos(x); }},
    {"tan", ModelFunction::kTan, 1, [](double x) { return std::tan(x); }},
    {"asin", ModelFunction::kAsin, 1, [](double x) { return std::asin(x); }},
    {"acos", ModelFunction::kAcos, 1, [](double x) { return std::acos(x); }},
    {"atan", ModelFunction::kAtan, 1, [](double x) { return std::atan(x); }},
    {"sinh", ModelFunction::kSinh, 1, [](double x) { return std::sinh(x); }},
    {"cosh", ModelFunction::kCosh, 1, [](double x) { return std::cosh(x); }},
    {"tanh", ModelFunction::kTanh, 1, [](double x) { return std::tanh(x); }},
    {"asinh", ModelFunction::kAsinh, 1, [](double x) { return std::asinh(x); }},
    {"acosh", ModelFunction::kAcosh, 1, [](double x) { return std::acosh(x); }},
    {"atanh", ModelFunction::kAtanh, 1, [](double x) { return std::atanh(x); }},
    {"exp", ModelFunction::kExp, 1, [](double x) { return std::exp(x); }},
    {"sqrt", ModelFunction::kSqrt, 1, [](double x) { return std::sqrt(x); }},
    {"log", ModelFunction::kLog, 1, [](double x) { return std::log(x); }},
    {"ln", ModelFunction::kLn, 1, [](double x) { return std::log(x); }},
    {"log10", ModelFunction::kLog10, 1, [](double x) { return std::log10(x); }},
    {"log2", ModelFunction::kLog2, 1, [](double x) { return std::log2(x); }},
    {"abs", ModelFunction::kAbs, 1, [](double x) { return std::fabs(x); }},
    {"sign", ModelFunction::kSign, 1,
     [](double x) { return x > 0.0 ? 1.0 : (x < 0.0 ? -1.0 : 0.0); }},
    {"rint", ModelFunction::kRint, 1, [](double x) { return std::floor(x + 0.5); }},
    {"atan2", ModelFunction::kAtan2, 2, nullptr},
    {"min", ModelFunction::kMin, -1, nullptr},
    {"max", ModelFunction::kMax, -1, nullptr},
    {"sum", ModelFunction::kSum, -1, nullptr},
    {"avg", ModelFunction::kAvg, -1, nullptr},
};

struct OperatorInfo {
  ModelOperator op;
  const char* text;
  double (*apply)(double, double);
};

constexpr OperatorInfo kOperators[] = {
    {ModelOperator::kOr, "||", [](double a, double b) -> double { return a != 0.0 || b != 0.0; }},
    {ModelOperator::kAnd, "&&", [](double a, double b) -> double { return a != 0.0 && b != 0.0; }},
    {ModelOperator::kEqual, "==", [](double a, double b) -> double { return a == b; }},
    {ModelOperator::kNotEqual, "!=", [](double a, double b) -> double { return a != b; }},
    {ModelOperator::kLessEqual, "<=", [](double a, double b) -> double { return a <= b; }},
    {ModelOperator::kGreaterEqual, ">=", [](double a, double b) -> double { return a >= b; }},
    {ModelOperator::kLess, "<", [](double a, double b) -> double { return a < b; }},
    {ModelOperator::kGreater, ">", [](double a, double b) -> double { return a > b; }},
    {ModelOperator::kAdd, "+", [](double a, double b) { return a + b; }},
    {ModelOperator::kSubtract, "-", [](double a, double b) { return a - b; }},
    {ModelOperator::kMultiply, "*", [](double a, double b) { return a * b; }},
    {ModelOperator::kDivide, "/", [](double a, double b) { return a / b; }},
};

// kOperators is in the order of ModelOperator, so an operator is its index.
constexpr bool InEnumOrder() {
  for (size_t i = 0; i < std::size(kOperators); ++i) {
    if (static_cast<size_t>(kOperators[i].op) != i) return false;
  }
  return true;
}
static_assert(InEnumOrder());

const OperatorInfo& Operator(ModelOperator op) { return kOperators[static_cast<size_t>(op)]; }

bool IsDigit(char c) { return c >= '0' && c <= '9'; }
bool IsNameStart(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; }
bool IsNameChar(char c) { return IsNameStart(c) || IsDigit(c); }

// A reading error: turned into the Error that ParseModel returns.
struct SyntaxError : std::runtime_error {
  SyntaxError(size_t at, const std::string& what)
      : std::runtime_error(fmt::format("column {}: {}", at + 1, what)), column(at + 1) {}
  size_t column;
};

// Recursive descent, one function per level of the grammar (model_grammar.hpp).
class Parser {
 public:
  Parser(const std::string& text, const std::vector<std::string>& names)
      : text_(text), names_(names) {
    syntax_.nodes.reserve(text.size() / 2 + 1);  // At most one node per token.
  }

  ModelSyntax Run() {
    Ternary();
    SkipSpace();
    if (pos_ != text_.size()) Fail(pos_, "unexpected '" + text_.substr(pos_, 1) + "'");
    return std::move(syntax_);
  }

 private:
  [[noreturn]] static void Fail(size_t at, const std::string& what) { throw SyntaxError(at, what); }

  // muparser skips every byte from 1 to 32 between tokens.
  void SkipSpace() {
    while (pos_ < text_.size() && text_[pos_] > 0 && text_[pos_] <= 0x20) ++pos_;
  }

  bool Accept(const char* op) {
    SkipSpace();
    const size_t n = std::char_traits<char>::length(op);
    if (text_.compare(pos_, n, op) != 0) return false;
    pos_ += n;
    return true;
  }

  const ModelNode& Node(size_t i) const { return syntax_.nodes[i]; }

  size_t Add(ModelNode node) {
    syntax_.nodes.push_back(std::move(node));
    return syntax_.nodes.size() - 1;
  }

  class Depth {
   public:
    Depth(int* depth, size_t at) : depth_(depth) {
      if (++*depth_ > kMaxModelDepth) {
        Fail(at, fmt::format("nested too deeply (parentheses, arguments and signs beyond {} "
                             "levels)",
                             kMaxModelDepth));
      }
    }
    ~Depth() { --*depth_; }
    Depth(const Depth&) = delete;
    Depth& operator=(const Depth&) = delete;

   private:
    int* depth_;
  };

  size_t Ternary() {
    const size_t lead = pos_;
    const Depth guard(&depth_, pos_);
    const size_t c = Or();
    SkipSpace();
    const size_t at = pos_;
    if (!Accept("?")) return c;
    const size_t a = Ternary();
    if (!Accept(":")) Fail(pos_, "expected ':' of '?'");
    const size_t b = Ternary();
    ModelNode node;
    node.kind = ModelNode::Kind::kIf;
    node.begin = Node(c).begin;
    node.end = Node(b).end;
    node.at = at;
    node.lead = lead;
    node.children = {c, a, b};
    return Add(std::move(node));
  }

  // One level of left-associative binary operators: `ops` are tried in order at each joint
  // (so "<=" before "<").
  template <typename Next>
  size_t Chain(Next next, std::initializer_list<ModelOperator> ops) {
    const size_t lead = pos_;
    const size_t first = (this->*next)();
    ModelNode node;  // Built at the first operator: most terms are one operand.
    for (;;) {
      SkipSpace();
      const size_t at = pos_;
      const ModelOperator* found = nullptr;
      for (const ModelOperator& op : ops) {
        const char* op_text = ModelOperatorText(op);
        if (pos_ < text_.size() && text_[pos_] == op_text[0] &&
            text_.compare(pos_, std::char_traits<char>::length(op_text), op_text) == 0) {
          found = &op;
          break;
        }
      }
      if (found == nullptr) break;
      pos_ += std::char_traits<char>::length(ModelOperatorText(*found));
      if (node.children.empty()) node.children.push_back(first);
      node.ops.push_back(*found);
      node.op_at.push_back(at);
      node.children.push_back((this->*next)());
    }
    if (node.children.empty()) return first;
    node.kind = ModelNode::Kind::kChain;
    node.lead = lead;
    node.begin = node.at = Node(first).begin;
    node.end = Node(node.children.back()).end;
    return Add(std::move(node));
  }

  size_t Or() { return Chain(&Parser::And, {ModelOperator::kOr}); }
  size_t And() { return Chain(&Parser::Compare, {ModelOperator::kAnd}); }
  size_t Compare() {
    return Chain(&Parser::Additive,
                 {ModelOperator::kEqual, ModelOperator::kNotEqual, ModelOperator::kLessEqual,
                  ModelOperator::kGreaterEqual, ModelOperator::kLess, ModelOperator::kGreater});
  }
  size_t Additive() {
    return Chain(&Parser::Product, {ModelOperator::kAdd, ModelOperator::kSubtract});
  }
  size_t Product() {
    return Chain(&Parser::Unary, {ModelOperator::kMultiply, ModelOperator::kDivide});
  }

  size_t Unary() {
    const Depth guard(&depth_, pos_);
    SkipSpace();
    const size_t at = pos_;
    if (pos_ < text_.size() && (text_[pos_] == '-' || text_[pos_] == '+')) {
      ModelNode node;
      node.kind = ModelNode::Kind::kSign;
      node.negative = text_[pos_++] == '-';
      const size_t operand = Unary();
      node.begin = at;
      node.end = Node(operand).end;
      node.at = at;
      node.children = {operand};
      return Add(std::move(node));
    }
    return Power();
  }

  size_t Power() {
    const size_t base = Primary();
    SkipSpace();
    const size_t at = pos_;
    if (!Accept("^")) return base;
    const size_t exponent = Unary();
    ModelNode node;
    node.kind = ModelNode::Kind::kPower;
    node.begin = Node(base).begin;
    node.end = Node(exponent).end;
    node.at = at;
    node.children = {base, exponent};
    return Add(std::move(node));
  }

  size_t Number() {
    const size_t at = pos_;
    size_t k = pos_;
    size_t digits = 0;
    for (; k < text_.size() && IsDigit(text_[k]); ++k) ++digits;
    if (k < text_.size() && text_[k] == '.') {
      for (++k; k < text_.size() && IsDigit(text_[k]); ++k) ++digits;
    }
    if (digits == 0) Fail(at, "expected a number");
    if (k < text_.size() && (text_[k] == 'e' || text_[k] == 'E')) {
      size_t e = k + 1;
      if (e < text_.size() && (text_[e] == '+' || text_[e] == '-')) ++e;
      const size_t first = e;
      while (e < text_.size() && IsDigit(text_[e])) ++e;
      if (e > first) k = e;  // "2e" is 2 followed by a name.
    }
    ModelNode node;
    node.kind = ModelNode::Kind::kNumber;
    node.text = text_.substr(at, k - at);
    node.number = std::strtod(node.text.c_str(), nullptr);
    node.begin = node.at = at;
    node.end = pos_ = k;
    return Add(std::move(node));
  }

  size_t Call(const std::string& name, size_t at) {
    ModelNode node;
    node.kind = ModelNode::Kind::kCall;
    node.text = name;
    if (!Accept(")")) {
      for (;;) {
        node.children.push_back(Ternary());
        if (Accept(",")) continue;
        if (Accept(")")) break;
        Fail(pos_, "expected ',' or ')' in the arguments of " + name + "()");
      }
    }
    const FunctionInfo* info = nullptr;
    for (const FunctionInfo& f : kFunctions) {
      if (name == f.name) info = &f;
    }
    if (info == nullptr) Fail(at, "the function " + name + "() is not in the model grammar");
    const size_t n = node.children.size();
    if (info->arity < 0 && n == 0) Fail(at, name + "() needs at least one argument");
    if (info->arity >= 0 && n != static_cast<size_t>(info->arity)) {
      Fail(at,
           fmt::format("{}() takes {} argument{}", name, info->arity, info->arity == 1 ? "" : "s"));
    }
    node.function = info->function;
    node.begin = node.at = at;
    node.end = pos_;
    return Add(std::move(node));
  }

  size_t Primary() {
    SkipSpace();
    const size_t at = pos_;
    if (pos_ >= text_.size()) Fail(at, "unexpected end of the model");
    const char c = text_[pos_];
    if (c == '(') {
      ++pos_;
      const size_t inner = Ternary();
      if (!Accept(")")) Fail(pos_, "expected ')'");
      syntax_.nodes[inner].begin = at;  // The parentheses belong to the term.
      syntax_.nodes[inner].end = pos_;
      return inner;
    }
    if (IsDigit(c) || c == '.') return Number();
    if (!IsNameStart(c)) Fail(at, "unexpected '" + std::string(1, c) + "'");
    size_t end = pos_;
    while (end < text_.size() && IsNameChar(text_[end])) ++end;
    const std::string name = text_.substr(pos_, end - pos_);
    pos_ = end;
    SkipSpace();
    if (pos_ < text_.size() && text_[pos_] == '(') {
      ++pos_;
      return Call(name, at);
    }
    ModelNode node;
    node.begin = node.at = at;
    node.end = end;
    for (size_t i = 0; i < names_.size(); ++i) {
      if (names_[i] != name) continue;
      node.kind = ModelNode::Kind::kInput;
      node.input = i;
      return Add(std::move(node));
    }
    if (name == "pi" || name == "_pi") {
      node.kind = ModelNode::Kind::kPi;
    } else if (name == "_e") {
      node.kind = ModelNode::Kind::kE;
    } else {
      Fail(at, "'" + name + "' is not an input");
    }
    return Add(std::move(node));
  }

  const std::string& text_;
  const std::vector<std::string>& names_;
  ModelSyntax syntax_;
  size_t pos_ = 0;
  int depth_ = 0;
};

double Evaluate(const ModelSyntax& syntax, size_t n, const double* x) {
  const ModelNode& node = syntax.nodes[n];
  const auto child = [&](size_t k) { return Evaluate(syntax, node.children[k], x); };
  switch (node.kind) {
    case ModelNode::Kind::kNumber:
      return node.number;
    case ModelNode::Kind::kInput:
      return x[node.input];
    case ModelNode::Kind::kPi:
      return kModelPi;
    case ModelNode::Kind::kE:
      return kModelE;
    case ModelNode::Kind::kSign:
      return node.negative ? -child(0) : child(0);
    case ModelNode::Kind::kPower:
      return std::pow(child(0), child(1));
    case ModelNode::Kind::kChain: {
      double v = child(0);
      for (size_t k = 0; k < node.ops.size(); ++k) v = ApplyOperator(node.ops[k], v, child(k + 1));
      return v;
    }
    case ModelNode::Kind::kIf:
      return child(0) != 0.0 ? child(1) : child(2);
    case ModelNode::Kind::kCall: {
      std::vector<double> args;
      for (size_t k = 0; k < node.children.size(); ++k) args.push_back(child(k));
      return ApplyFunction(node.function, args);
    }
  }
  return std::nan("");
}

}  // namespace

Result<ModelSyntax> ParseModel(const std::string& text, const std::vector<std::string>& names) {
  try {
    return Parser(text, names).Run();
  } catch (const SyntaxError& e) {
    Error error = MakeError(e.what());
    error.column = static_cast<int64_t>(e.column);
    return error;
  }
}

const char* ModelOperatorText(ModelOperator op) { return Operator(op).text; }

double ApplyOperator(ModelOperator op, double a, double b) { return Operator(op).apply(a, b); }

double ApplyFunction(ModelFunction function, const std::vector<double>& args) {
  for (const FunctionInfo& f : kFunctions) {
    if (f.function == function && f.apply != nullptr) return f.apply(args[0]);
  }
  if (function == ModelFunction::kAtan2) return std::atan2(args[0], args[1]);
  double v = args[0];  // min, max, sum, avg.
  for (size_t i = 1; i < args.size(); ++i) {
    if (function == ModelFunction::kMin) v = std::fmin(v, args[i]);
    if (function == ModelFunction::kMax) v = std::fmax(v, args[i]);
    if (function == ModelFunction::kSum || function == ModelFunction::kAvg) v += args[i];
  }
  return function == ModelFunction::kAvg ? v / static_cast<double>(args.size()) : v;
}

double EvaluateModel(const ModelSyntax& syntax, const double* x) {
  return Evaluate(syntax, syntax.root(), x);
}

}  // namespace internal
}  // namespace metro
