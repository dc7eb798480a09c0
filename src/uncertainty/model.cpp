#include "uncertainty/model.hpp"

#include <fmt/format.h>
#include <muParser.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <utility>

#include "metro/core/terminal_text.hpp"

namespace metro {
namespace internal {
namespace {

bool IsIdentifier(const std::string& name) {
  if (name.empty()) return false;
  const auto alpha = [](char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); };
  if (!alpha(name[0]) && name[0] != '_') return false;
  for (const char c : name) {
    if (!alpha(c) && c != '_' && !(c >= '0' && c <= '9')) return false;
  }
  return true;
}

// An error about the model's text at byte `at` of it (npos: the whole model): the message
// says what without quoting the model, and column = at + 1 (0 for the whole model) tells the
// budget where (model.hpp, "Errors").
Error ModelTextError(size_t at, std::string what) {
  Error e = MakeError(std::move(what));
  e.column = at == std::string::npos ? 0 : static_cast<int64_t>(at) + 1;
  return e;
}

// The first place `name` stands as a whole identifier in `expression` (npos when none).
size_t IdentifierAt(const std::string& expression, const std::string& name) {
  const auto part = [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
  };
  for (size_t at = expression.find(name); at != std::string::npos;
       at = expression.find(name, at + 1)) {
    const size_t end = at + name.size();
    if ((at == 0 || !part(expression[at - 1])) &&
        (end >= expression.size() || !part(expression[end]))) {
      return at;
    }
  }
  return std::string::npos;
}

// muparser's message with its token quoted once and short: a message that holds the token
// ("Unexpected token "x" found at position 4") gets the token cut to 40 bytes in place; a
// message without it ("Expression too long.") gets none (the budget quotes the model).
std::string MuParserMessage(const mu::Parser::exception_type& e) {
  std::string message = e.GetMsg();
  const std::string token = e.GetToken();
  if (const size_t at = token.empty() ? std::string::npos : message.find(token);
      at != std::string::npos && token.size() > 40) {
    message.replace(at, token.size(), Excerpt(token, 0, 40));
  }
  return message;
}

bool SameValue(double a, double b) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  if (std::isinf(a) || std::isinf(b)) return a == b;
  return std::fabs(a - b) <= 1e-12 * std::fmax(1.0, std::fmax(std::fabs(a), std::fabs(b)));
}

}  // namespace

// One muparser object bound to its own variable storage (vars never reallocates).
struct MeasurementModel::ScalarParser {
  mu::Parser parser;
  std::vector<double> vars;
};

namespace {

// Where muparser 2.3.3 departs from the model grammar (model_grammar.hpp), metro gives it the
// grammar's meaning: pi and _pi are pi (built with GCC it defines _pi as 3.141592653589, 7.9e-13
// below pi: 2*_pi*f at 1e7 Hz was 2.5 u(f = 1 uHz) low), and asinh, acosh, atanh are the C
// library's (it computes them as logarithms: asinh(1e-10) 8e-8 high, asinh(-1e8) = -inf). An
// input called pi replaces pi; muparser refuses an input called _pi (its constant's name).
void DefineGrammar(const std::vector<std::string>& names, mu::Parser* parser) {
  for (const char* constant : {"pi", "_pi"}) {
    if (std::find(names.begin(), names.end(), constant) == names.end()) {
      parser->DefineConst(constant, 3.14159265358979323846);
    }
  }
  using F = double (*)(double);
  parser->DefineFun("asinh", static_cast<F>(std::asinh));
  parser->DefineFun("acosh", static_cast<F>(std::acosh));
  parser->DefineFun("atanh", static_cast<F>(std::atanh));
}

std::unique_ptr<MeasurementModel::ScalarParser> NewParser(const std::string& expression,
                                                          const std::vector<std::string>& names,
                                                          std::string* why);

}  // namespace

// The bytecode translated to whole-block operations. Each instruction pushes or combines
// rows of a stack of arrays; semantics follow muparser's ParseCmdCodeShort().
class BlockProgram {
 public:
  enum class Kind { kVar, kVal, kVarPow, kVarMul, kBinary, kFunc, kMultiFunc };
  struct Instruction {
    Kind kind = Kind::kVal;
    mu::ECmdCode cmd = mu::cmUNKNOWN;
    size_t var = 0;
    int power = 1;
    int argc = 0;
    double a = 0.0;
    double b = 0.0;
    mu::generic_callable_type callable{};
  };

  // Null when the bytecode holds an operation this translation does not cover.
  static std::shared_ptr<const BlockProgram> Translate(const MeasurementModel::ScalarParser& p) {
    auto program = std::make_shared<BlockProgram>();
    const mu::ParserByteCode& code = p.parser.GetByteCode();
    const mu::SToken* token = code.GetBase();
    const double* first = p.vars.data();
    const double* last = first + p.vars.size();
    int depth = 0;
    int max_depth = 0;
    const auto var_index = [&](const double* ptr, size_t* index) {
      if (ptr < first || ptr >= last) return false;
      *index = static_cast<size_t>(ptr - first);
      return true;
    };
    for (size_t i = 0; i < code.GetSize(); ++i, ++token) {
      Instruction in;
      in.cmd = token->Cmd;
      switch (token->Cmd) {
        case mu::cmVAR:
          in.kind = Kind::kVar;
          if (!var_index(token->Val.ptr, &in.var)) return nullptr;
          ++depth;
          break;
        case mu::cmVAL:
          in.kind = Kind::kVal;
          in.a = token->Val.data2;
          ++depth;
          break;
        case mu::cmVARPOW2:
        case mu::cmVARPOW3:
        case mu::cmVARPOW4:
          in.kind = Kind::kVarPow;
          in.power = token->Cmd == mu::cmVARPOW2 ? 2 : token->Cmd == mu::cmVARPOW3 ? 3 : 4;
          if (!var_index(token->Val.ptr, &in.var)) return nullptr;
          ++depth;
          break;
        case mu::cmVARMUL:
          in.kind = Kind::kVarMul;
          in.a = token->Val.data;
          in.b = token->Val.data2;
          if (!var_index(token->Val.ptr, &in.var)) return nullptr;
          ++depth;
          break;
        case mu::cmLE:
        case mu::cmGE:
        case mu::cmNEQ:
        case mu::cmEQ:
        case mu::cmLT:
        case mu::cmGT:
        case mu::cmADD:
        case mu::cmSUB:
        case mu::cmMUL:
        case mu::cmDIV:
        case mu::cmPOW:
        case mu::cmLAND:
        case mu::cmLOR:
          in.kind = Kind::kBinary;
          --depth;
          break;
        case mu::cmFUNC:
          in.callable = token->Fun.cb;
          in.argc = token->Fun.argc;
          if (in.argc >= 0) {
            if (in.argc > 3) return nullptr;
            in.kind = Kind::kFunc;
            depth += 1 - in.argc;
          } else {
            in.kind = Kind::kMultiFunc;
            depth += 1 + in.argc;
          }
          break;
        case mu::cmEND:
          i = code.GetSize();
          continue;
        default:
          return nullptr;  // if-then-else, assignment, string and bulk functions.
      }
      if (depth < 1 && !(in.kind == Kind::kFunc && in.argc == 0)) return nullptr;
      max_depth = std::max(max_depth, depth);
      program->code_.push_back(in);
    }
    if (depth != 1) return nullptr;
    program->max_depth_ = static_cast<size_t>(max_depth);
    return program;
  }

  size_t max_depth() const { return max_depth_; }

  // stack holds max_depth() rows of n values.
  void Run(const double* const* inputs, size_t n, double* stack, double* out) const {
    size_t top = 0;  // Number of occupied rows.
    const auto row = [&](size_t r) { return stack + r * n; };
    for (const Instruction& in : code_) {
      switch (in.kind) {
        case Kind::kVar: {
          double* d = row(top++);
          const double* x = inputs[in.var];
          for (size_t k = 0; k < n; ++k) d[k] = x[k];
          break;
        }
        case Kind::kVal: {
          double* d = row(top++);
          for (size_t k = 0; k < n; ++k) d[k] = in.a;
          break;
        }
        case Kind::kVarPow: {
          double* d = row(top++);
          const double* x = inputs[in.var];
          if (in.power == 2) {
            for (size_t k = 0; k < n; ++k) d[k] = x[k] * x[k];
          } else if (in.power == 3) {
            for (size_t k = 0; k < n; ++k) d[k] = x[k] * x[k] * x[k];
          } else {
            for (size_t k = 0; k < n; ++k) d[k] = x[k] * x[k] * x[k] * x[k];
          }
          break;
        }
        case Kind::kVarMul: {
          double* d = row(top++);
          const double* x = inputs[in.var];
          for (size_t k = 0; k < n; ++k) d[k] = x[k] * in.a + in.b;
          break;
        }
        case Kind::kBinary: {
          --top;
          double* l = row(top - 1);
          const double* r = row(top);
          RunBinary(in.cmd, l, r, n);
          break;
        }
        case Kind::kFunc: {
          if (in.argc == 0) {
            double* d = row(top++);
            for (size_t k = 0; k < n; ++k) d[k] = in.callable.call_fun<0>();
          } else if (in.argc == 1) {
            double* d = row(top - 1);
            for (size_t k = 0; k < n; ++k) d[k] = in.callable.call_fun<1>(d[k]);
          } else if (in.argc == 2) {
            top -= 1;
            double* d = row(top - 1);
            const double* e = row(top);
            for (size_t k = 0; k < n; ++k) d[k] = in.callable.call_fun<2>(d[k], e[k]);
          } else {
            top -= 2;
            double* d = row(top - 1);
            const double* e = row(top);
            const double* f = row(top + 1);
            for (size_t k = 0; k < n; ++k) d[k] = in.callable.call_fun<3>(d[k], e[k], f[k]);
          }
          break;
        }
        case Kind::kMultiFunc: {
          const size_t argc = static_cast<size_t>(-in.argc);
          top -= argc - 1;
          const size_t base = top - 1;
          std::vector<double> args(argc);
          for (size_t k = 0; k < n; ++k) {
            for (size_t j = 0; j < argc; ++j) args[j] = row(base + j)[k];
            row(base)[k] = in.callable.call_multfun(args.data(), static_cast<int>(argc));
          }
          break;
        }
      }
    }
    const double* result = row(0);
    for (size_t k = 0; k < n; ++k) out[k] = result[k];
  }

 private:
  static void RunBinary(mu::ECmdCode cmd, double* l, const double* r, size_t n) {
    switch (cmd) {
      case mu::cmADD:
        for (size_t k = 0; k < n; ++k) l[k] += r[k];
        break;
      case mu::cmSUB:
        for (size_t k = 0; k < n; ++k) l[k] -= r[k];
        break;
      case mu::cmMUL:
        for (size_t k = 0; k < n; ++k) l[k] *= r[k];
        break;
      case mu::cmDIV:
        for (size_t k = 0; k < n; ++k) l[k] /= r[k];
        break;
      case mu::cmPOW:
        for (size_t k = 0; k < n; ++k) l[k] = std::pow(l[k], r[k]);
        break;
      case mu::cmLE:
        for (size_t k = 0; k < n; ++k) l[k] = l[k] <= r[k];
        break;
      case mu::cmGE:
        for (size_t k = 0; k < n; ++k) l[k] = l[k] >= r[k];
        break;
      case mu::cmNEQ:
        for (size_t k = 0; k < n; ++k) l[k] = l[k] != r[k];
        break;
      case mu::cmEQ:
        for (size_t k = 0; k < n; ++k) l[k] = l[k] == r[k];
        break;
      case mu::cmLT:
        for (size_t k = 0; k < n; ++k) l[k] = l[k] < r[k];
        break;
      case mu::cmGT:
        for (size_t k = 0; k < n; ++k) l[k] = l[k] > r[k];
        break;
      case mu::cmLAND:
        for (size_t k = 0; k < n; ++k) l[k] = (l[k] != 0.0) && (r[k] != 0.0);
        break;
      case mu::cmLOR:
        for (size_t k = 0; k < n; ++k) l[k] = (l[k] != 0.0) || (r[k] != 0.0);
        break;
      default:
        METRO_CHECK(false);
    }
  }

  std::vector<Instruction> code_;
  size_t max_depth_ = 0;
};

namespace {

double* CollectUndefined(const mu::char_type* name, void* user) {
  auto* store = static_cast<std::pair<std::vector<std::string>, std::deque<double>>*>(user);
  store->first.emplace_back(name);
  store->second.push_back(0.0);
  return &store->second.back();
}

std::unique_ptr<MeasurementModel::ScalarParser> NewParser(const std::string& expression,
                                                          const std::vector<std::string>& names,
                                                          std::string* why) {
  auto p = std::make_unique<MeasurementModel::ScalarParser>();
  p->vars.assign(names.size(), 1.0);
  try {
    for (size_t i = 0; i < names.size(); ++i) p->parser.DefineVar(names[i], &p->vars[i]);
    DefineGrammar(names, &p->parser);
    p->parser.SetExpr(expression);
    p->parser.Eval();
    if (p->parser.GetNumResults() != 1) {
      *why = "the model must be one expression, not a comma-separated list";
      return nullptr;
    }
  } catch (const mu::Parser::exception_type& e) {
    *why = MuParserMessage(e);
    return nullptr;
  }
  return p;
}

class ParserEvaluator final : public MeasurementModel::Evaluator {
 public:
  explicit ParserEvaluator(std::unique_ptr<MeasurementModel::ScalarParser> p) : p_(std::move(p)) {}
  void EvaluateBlock(const double* const* inputs, size_t n, double* out) override {
    const size_t count = p_->vars.size();
    for (size_t k = 0; k < n; ++k) {
      for (size_t i = 0; i < count; ++i) p_->vars[i] = inputs[i][k];
      try {
        out[k] = p_->parser.Eval();
      } catch (const mu::Parser::exception_type&) {
        out[k] = std::nan("");
      }
    }
  }

 private:
  std::unique_ptr<MeasurementModel::ScalarParser> p_;
};

class ProgramEvaluator final : public MeasurementModel::Evaluator {
 public:
  explicit ProgramEvaluator(std::shared_ptr<const BlockProgram> program)
      : program_(std::move(program)) {}
  void EvaluateBlock(const double* const* inputs, size_t n, double* out) override {
    const size_t need = program_->max_depth() * n;
    if (stack_.size() < need) stack_.resize(need);
    program_->Run(inputs, n, stack_.data(), out);
  }

 private:
  std::shared_ptr<const BlockProgram> program_;
  std::vector<double> stack_;
};

class LinearEvaluator final : public MeasurementModel::Evaluator {
 public:
  explicit LinearEvaluator(std::vector<double> c) : c_(std::move(c)) {}
  void EvaluateBlock(const double* const* inputs, size_t n, double* out) override {
    for (size_t k = 0; k < n; ++k) out[k] = 0.0;
    for (size_t i = 0; i < c_.size(); ++i) {
      const double c = c_[i];
      const double* x = inputs[i];
      for (size_t k = 0; k < n; ++k) out[k] += c * x[k];
    }
  }

 private:
  std::vector<double> c_;
};

}  // namespace

MeasurementModel::MeasurementModel(MeasurementModel&&) noexcept = default;
MeasurementModel& MeasurementModel::operator=(MeasurementModel&&) noexcept = default;
MeasurementModel::~MeasurementModel() = default;

Result<MeasurementModel> MeasurementModel::FromExpression(const std::string& expression,
                                                          const std::vector<std::string>& names) {
  for (const auto& name : names) {
    if (!IsIdentifier(name)) {
      return MakeError("input '" + name +
                       "': a name used in a model must be a letter or '_' followed by letters, "
                       "digits or '_'");
    }
  }
  // A model is one expression without side effects: muparser's assignment (`x=5`, which
  // would overwrite an input and report y = 5 +- 0) is refused; ==, <=, >= and != compare.
  for (size_t i = 0; i < expression.size(); ++i) {
    if (expression[i] != '=') continue;
    const char before = i > 0 ? expression[i - 1] : '\0';
    const char after = i + 1 < expression.size() ? expression[i + 1] : '\0';
    if (after == '=') {
      ++i;  // ==
      continue;
    }
    if (before == '<' || before == '>' || before == '!') continue;
    return ModelTextError(
        i, fmt::format("'=' at position {} assigns; a model is one expression of its inputs (no "
                       "assignment: write the right-hand side alone, or == to compare)",
                       i + 1));
  }
  // muparser refuses an expression of MaxLenExpression (20000) bytes or more with its whole
  // text as the token (a 1 MB model was echoed twice in one message).
  const size_t longest = static_cast<size_t>(mu::MaxLenExpression) - 1;
  if (expression.size() > longest) {
    return ModelTextError(
        longest, fmt::format("{} bytes; muparser reads a model of at most {} bytes (write a "
                             "shorter expression, e.g. with fewer terms or shorter input names)",
                             expression.size(), longest));
  }
  // Pass 1: find identifiers that are not inputs (muparser calls the factory for them).
  std::pair<std::vector<std::string>, std::deque<double>> unknown;
  try {
    mu::Parser probe;
    std::vector<double> dummy(names.size(), 1.0);
    for (size_t i = 0; i < names.size(); ++i) probe.DefineVar(names[i], &dummy[i]);
    DefineGrammar(names, &probe);
    probe.SetVarFactory(CollectUndefined, &unknown);
    probe.SetExpr(expression);
    probe.GetUsedVar();
    if (unknown.first.empty()) {
      probe.Eval();
      if (probe.GetNumResults() > 1) {
        return ModelTextError(
            expression.find(','),
            fmt::format("{} comma-separated expressions; a model is one expression (commas "
                        "only between a function's arguments, e.g. max(a, b))",
                        probe.GetNumResults()));
      }
    }
  } catch (const mu::Parser::exception_type& e) {
    const std::string token = e.GetToken();
    const std::string message = MuParserMessage(e);
    const bool quoted = token.empty() || message.find(Excerpt(token, 0, 40)) != std::string::npos;
    return ModelTextError(e.GetPos() >= 0 ? static_cast<size_t>(e.GetPos()) : std::string::npos,
                          quoted ? message : message + " (near '" + Excerpt(token, 0, 40) + "')");
  }
  if (!unknown.first.empty()) {
    std::string list;
    for (const auto& name : unknown.first) list += (list.empty() ? "'" : ", '") + name + "'";
    return ModelTextError(
        IdentifierAt(expression, unknown.first.front()),
        "uses " + list +
            (unknown.first.size() == 1 ? ", which is not an input" : ", which are not inputs"));
  }
  std::string why;
  auto parser = NewParser(expression, names, &why);
  if (!parser) return ModelTextError(std::string::npos, why);

  MeasurementModel model;
  model.expression_ = expression;
  model.names_ = names;
  model.input_count_ = names.size();
  for (const auto& [name, ptr] : parser->parser.GetUsedVar()) {
    (void)ptr;
    model.used_names_.push_back(name);
  }
  model.program_ = BlockProgram::Translate(*parser);
  model.scalar_ = std::move(parser);
  if (model.program_) {
    // Check the translation against muparser at a few points, NaN included.
    const size_t n = 5;
    std::vector<std::vector<double>> columns(names.size(), std::vector<double>(n));
    for (size_t i = 0; i < names.size(); ++i) {
      for (size_t k = 0; k < n; ++k) {
        columns[i][k] = 0.37 + 0.61 * static_cast<double>(k) - 0.13 * static_cast<double>(i);
      }
    }
    std::vector<const double*> inputs;
    for (const auto& c : columns) inputs.push_back(c.data());
    std::vector<double> block(n);
    ProgramEvaluator(model.program_).EvaluateBlock(inputs.data(), n, block.data());
    std::vector<double> x(names.size());
    for (size_t k = 0; k < n && model.program_; ++k) {
      for (size_t i = 0; i < names.size(); ++i) x[i] = columns[i][k];
      if (!SameValue(model.Evaluate(x.data()), block[k])) model.program_.reset();
    }
  }
  return model;
}

MeasurementModel MeasurementModel::Linear(std::vector<double> coefficients) {
  MeasurementModel model;
  model.input_count_ = coefficients.size();
  model.coefficients_ = std::move(coefficients);
  return model;
}

bool MeasurementModel::vectorized() const { return is_linear() || program_ != nullptr; }

double MeasurementModel::Evaluate(const double* x) const {
  if (is_linear()) {
    double y = 0.0;
    for (size_t i = 0; i < coefficients_.size(); ++i) y += coefficients_[i] * x[i];
    return y;
  }
  for (size_t i = 0; i < input_count_; ++i) scalar_->vars[i] = x[i];
  try {
    return scalar_->parser.Eval();
  } catch (const mu::Parser::exception_type&) {
    return std::nan("");
  }
}

std::unique_ptr<MeasurementModel::Evaluator> MeasurementModel::MakeEvaluator() const {
  if (is_linear()) return std::make_unique<LinearEvaluator>(coefficients_);
  if (program_) return std::make_unique<ProgramEvaluator>(program_);
  std::string why;
  auto parser = NewParser(expression_, names_, &why);
  METRO_CHECK(parser != nullptr);  // The same expression parsed in FromExpression().
  return std::make_unique<ParserEvaluator>(std::move(parser));
}

}  // namespace internal
}  // namespace metro
