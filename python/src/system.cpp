// xpbd_bench.System: a captured linear step (harness/io/system_io.hpp) with both forms'
// matrices as scipy/numpy objects. Matrices and vectors the object holds are views (no copy)
// that keep the object alive.
#include "bindings.hpp"
#include "convert.hpp"

#include "harness/io/system_io.hpp"
#include "problems/primal_system.hpp"

#include <nanobind/stl/string.h>

#include <optional>

namespace xb::py {

namespace {

struct System {
  std::string path;
  CapturedSystem sys;
  SparseMatrix J;                      // ∇C, m × 3n (empty without primal data)
  std::optional<PrimalSystem> primal;  // K, when the primal form exists (primal data, every α̃ > 0)
  Vector f;                            // K's right-hand side Jᵀα̃⁻¹b
  Eigen::MatrixXd modes;               // K's near-kernel: the rigid modes at the positions
};

System load(const std::string& path) {
  System s;
  s.path = path;
  s.sys = read_system_h5(path);
  if (s.sys.has_primal()) {
    s.J = jacobian_csr(s.sys.graph, s.sys.grad);
    s.J.makeCompressed();
    if ((s.sys.alpha_tilde.array() > 0).all()) {
      s.primal.emplace(s.sys.graph);
      s.primal->fill(s.sys.grad, s.sys.alpha_tilde);
      s.primal->rhs(s.sys.grad, s.sys.alpha_tilde, s.sys.b, s.f);
      s.modes = s.primal->rigid_modes(s.sys.x);
    }
  }
  return s;
}

nb::object self_of(const System& s) { return nb::borrow(nb::find(&s)); }

}  // namespace

void bind_system(nb::module_& m) {
  nb::class_<System>(m, "System", nb::dynamic_attr(),
                     "A captured linear step: the dual system (A, b), its primal form (K, f) and what both are built "
                     "from (J, inv_mass, alpha_tilde, positions). Load with load_system(path) or capture().")
      .def_ro("path", &System::path, "the .h5 file it was read from")
      .def_prop_ro("A", [](const System& s) { return csr_view(s.sys.A, self_of(s)); },
                   "the dual matrix J M^-1 J^T + alpha~ (scipy.sparse.csr_matrix, both triangles)")
      .def_prop_ro("b", [](const System& s) { return vector_view(s.sys.b.data(), s.sys.b.size(), self_of(s)); },
                   "the dual right-hand side -(C + alpha~ lambda)")
      .def_prop_ro("K", [](const System& s) { return s.primal ? csr_view(s.primal->K(), self_of(s)) : nb::none(); },
                   "the primal matrix M + J^T alpha~^-1 J over the free particles (3 rows each), or None")
      .def_prop_ro("f", [](const System& s) { return s.primal ? vector_view(s.f.data(), s.f.size(), self_of(s)) : nb::none(); },
                   "the primal right-hand side J^T alpha~^-1 b, or None")
      .def_prop_ro("J", [](const System& s) { return s.J.rows() ? csr_view(s.J, self_of(s)) : nb::none(); },
                   "the constraint gradients, m x 3n (columns 3p..3p+2: particle p), or None")
      .def_prop_ro("inv_mass", [](const System& s) { return vector_copy(s.sys.graph.w); },
                   "per particle (n): 1/mass, 0 for a pinned particle; M^-1 of J's columns is each repeated 3 times")
      .def_prop_ro("alpha_tilde",
                   [](const System& s) { return vector_view(s.sys.alpha_tilde.data(), s.sys.alpha_tilde.size(), self_of(s)); },
                   "per constraint: the scaled compliance alpha / h^2")
      .def_prop_ro("positions", [](const System& s) { return positions_copy(s.sys.x); }, "the particles' positions (n, 3)")
      .def_prop_ro("rigid_modes", [](const System& s) { return s.primal ? matrix_copy(s.modes) : nb::none(); },
                   "K's near-kernel (rows of K x 6): translations x, y, z, then rotations; or None")
      .def_prop_ro("free_particles",
                   [](const System& s) {
                     if (!s.primal) return nb::object(nb::none());
                     const auto& fp = s.primal->free_particles();
                     return vector_copy(Eigen::Map<const Eigen::VectorXi>(fp.data(), static_cast<Eigen::Index>(fp.size())).cast<double>())
                         .attr("astype")("int64");
                   },
                   "the particle of each 3-row block of K, or None")
      .def_prop_ro("attrs",
                   [](const System& s) {
                     nb::dict d;
                     for (const auto& [k, v] : s.sys.attrs) d[k.c_str()] = attr_to_python(v);
                     return d;
                   },
                   "the capture's attributes: scene, frame, substep, iteration, every parameter, provenance")
      .def("__repr__", [](const System& s) {
        return "<xpbd_bench.System " + s.path + ": " + std::to_string(s.sys.A.rows()) + " rows" +
               (s.primal ? ", primal " + std::to_string(s.primal->rows()) + " rows" : std::string()) + ">";
      });
  m.def("load_system", &load, nb::arg("path"), "Reads a system written by capture (PREFIX.h5).");
}

}  // namespace xb::py
