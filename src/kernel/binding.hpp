// What every binding file of dualarm_qp._kernel shares: nanobind, NumPy's C API for the
// arrays the kernel returns (out() for a function that returns one array, view() and
// array_property() for the arrays of a bound struct: a result of several values is a
// struct with named properties, never a tuple), and the conversions of its arguments.
// module.cpp makes the module and calls each file's bind_*() function.
#pragma once

#include <stdexcept>
#include <string>

#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include <cstdint>
#include <type_traits>

// NumPy's C API, for the arrays the kernel returns (out() below). Built with NumPy 2's
// headers (CMakeLists.txt checks), for NumPy 1.23 and later at run time (the project
// requires 1.24 or later): a later default of the headers would refuse NumPy 1.x. One
// table of the API for the whole module: module.cpp imports it (DQK_BINDING_MAIN), the
// other binding files use it.
#define NPY_NO_DEPRECATED_API NPY_1_23_API_VERSION
#define NPY_TARGET_VERSION NPY_1_23_API_VERSION
#define PY_ARRAY_UNIQUE_SYMBOL DQK_NUMPY_API
#ifndef DQK_BINDING_MAIN
#define NO_IMPORT_ARRAY
#endif
#include <numpy/arrayobject.h>

#include "boxes.hpp"
#include "capsules.hpp"
#include "certified_step.hpp"
#include "certify.hpp"
#include "clearance.hpp"
#include "kinematics.hpp"
#include "linalg.hpp"
#include "rows.hpp"

namespace dqk_binding {

namespace nb = nanobind;
using dqk::Index;
using dqk::Mat;
using dqk::Vec;
// A matrix argument as numpy holds it, C- or Fortran-ordered, without a copy through
// Python (a `const Mat&` parameter makes nanobind call numpy to re-order a C-ordered
// array: about 2 us per argument); the kernel's functions copy it in C++ as needed.
// Eigen reads a zero stride as the default one: a broadcast view must not come here
// (StepProblem and the Python wrappers hand over C-ordered arrays).
using In = nb::DRef<const Mat>;

// NumPy's type number of an output's scalar.
template <typename S>
constexpr int numpy_type() {
  if constexpr (std::is_same_v<S, double>) {
    return NPY_DOUBLE;
  } else if constexpr (std::is_same_v<S, bool>) {
    return NPY_BOOL;
  } else if constexpr (std::is_same_v<S, std::int8_t>) {
    return NPY_INT8;
  } else if constexpr (std::is_same_v<S, std::uint8_t>) {
    return NPY_UINT8;
  } else if constexpr (std::is_same_v<S, std::int64_t>) {
    return NPY_INT64;
  } else {
    static_assert(std::is_same_v<S, std::int32_t>, "out(): a scalar type NumPy is not told");
    return NPY_INT32;
  }
}

// A result handed to Python without a copy: the Eigen value is moved to the heap and a
// numpy array made by NumPy's C API views it, a capsule that deletes it as its base.
// (nanobind's own export, nb::ndarray<nb::numpy>, took about 0.3 us per array against
// 0.1 us here; a step returns some thirty arrays. Below 1 kB nanobind would even copy an
// Eigen result through numpy.copy, a Python call of about 1.5 us.)
template <typename M>
nb::object out(M&& value) {
  using T = std::decay_t<M>;
  using S = typename T::Scalar;
  constexpr int nd = T::ColsAtCompileTime == 1 ? 1 : 2;
  npy_intp shape[2] = {static_cast<npy_intp>(nd == 1 ? value.size() : value.rows()),
                       static_cast<npy_intp>(nd == 1 ? 1 : value.cols())};
  if (value.size() == 0) {  // nothing to view: NumPy's own empty array
    PyObject* empty = PyArray_Zeros(nd, shape, PyArray_DescrFromType(numpy_type<S>()), 0);
    if (empty == nullptr) throw nb::python_error();
    return nb::steal(empty);
  }
  T* heap = new T(std::forward<M>(value));
  PyObject* owner = PyCapsule_New(heap, nullptr, [](PyObject* capsule) {
    delete static_cast<T*>(PyCapsule_GetPointer(capsule, nullptr));
  });
  if (owner == nullptr) {
    delete heap;
    throw nb::python_error();
  }
  npy_intp strides[2] = {static_cast<npy_intp>(sizeof(S)), 0};
  if constexpr (nd == 2) {
    strides[0] = static_cast<npy_intp>(heap->rowStride() * sizeof(S));
    strides[1] = static_cast<npy_intp>(heap->colStride() * sizeof(S));
  }
  PyObject* array = PyArray_New(&PyArray_Type, nd, shape, numpy_type<S>(), strides,
                                heap->data(), 0, NPY_ARRAY_WRITEABLE | NPY_ARRAY_ALIGNED,
                                nullptr);
  if (array == nullptr) {
    Py_DECREF(owner);
    throw nb::python_error();
  }
  if (PyArray_SetBaseObject(reinterpret_cast<PyArrayObject*>(array), owner) < 0) {
    Py_DECREF(array);
    throw nb::python_error();
  }
  return nb::steal(array);
}

// A numpy array viewing value, a member of the object owner (kept alive by the array):
// how a bound struct hands out its arrays, each property read a new array over the same
// memory. Writeable, as numpy's own arrays are (some QP backends refuse read-only
// buffers): the kernel's results are made anew by each call, so a write changes that
// result only.
template <typename M>
nb::object view(const M& value, nb::handle owner) {
  using S = typename M::Scalar;
  constexpr int nd = M::ColsAtCompileTime == 1 ? 1 : 2;
  npy_intp shape[2] = {static_cast<npy_intp>(nd == 1 ? value.size() : value.rows()),
                       static_cast<npy_intp>(nd == 1 ? 1 : value.cols())};
  npy_intp strides[2] = {static_cast<npy_intp>(sizeof(S)), 0};
  if constexpr (nd == 2) {
    strides[0] = static_cast<npy_intp>(value.rowStride() * sizeof(S));
    strides[1] = static_cast<npy_intp>(value.colStride() * sizeof(S));
  }
  if (value.size() == 0) {  // no memory to view: a fresh empty array of the shape
    PyObject* empty = PyArray_Zeros(nd, shape, PyArray_DescrFromType(numpy_type<S>()), 0);
    if (empty == nullptr) throw nb::python_error();
    return nb::steal(empty);
  }
  PyObject* array = PyArray_New(&PyArray_Type, nd, shape, numpy_type<S>(), strides,
                                const_cast<S*>(value.data()), 0,
                                NPY_ARRAY_ALIGNED | NPY_ARRAY_WRITEABLE, nullptr);
  if (array == nullptr) throw nb::python_error();
  owner.inc_ref();
  if (PyArray_SetBaseObject(reinterpret_cast<PyArrayObject*>(array), owner.ptr()) < 0) {
    owner.dec_ref();
    Py_DECREF(array);
    throw nb::python_error();
  }
  return nb::steal(array);
}

// Binds the read-only array property name of T, the member the getter returns.
template <typename T, typename Get>
void array_property(nb::class_<T>& cls, const char* name, Get get, const char* doc) {
  cls.def_prop_ro(
      name, [get](nb::handle self) { return view(get(nb::cast<const T&>(self)), self); }, doc);
}

// The same for a member of T named by its pointer (array_property(cls, "x", &T::x, doc)).
template <typename T, typename M>
void array_property(nb::class_<T>& cls, const char* name, M T::*member, const char* doc) {
  cls.def_prop_ro(
      name, [member](nb::handle self) { return view(nb::cast<const T&>(self).*member, self); },
      doc);
}

inline void require(bool ok, const char* what) {
  if (!ok) throw std::invalid_argument(what);
}

// A C-ordered float64 matrix (rows, cols) as numpy holds it: nanobind copies any other
// array (Fortran-ordered, strided, broadcast) into one before the call, so a zero stride
// never reaches Eigen (which would read it as the default stride).
using CArray = nb::ndarray<const double, nb::ndim<2>, nb::c_contig, nb::device::cpu>;
using CMap = Eigen::Map<const dqk::RowMat>;
using PointsMap = Eigen::Map<const dqk::Points>;

inline CMap c_matrix(const CArray& a, Index cols, const char* name) {
  const auto c = static_cast<Index>(a.shape(1));
  if (cols >= 0 && c != cols)
    throw std::invalid_argument(std::string(name) + " must have " + std::to_string(cols) +
                                " columns");
  return CMap(a.data(), static_cast<Index>(a.shape(0)), c);
}

inline PointsMap points(const CArray& a, const char* name) {
  c_matrix(a, 3, name);
  return PointsMap(a.data(), static_cast<Index>(a.shape(0)), 3);
}

// A basis (basis(A)'s answer) checked against the A it is used with.
inline const dqk::Basis& basis_of(const In& A, const dqk::Basis& f) {
  require(f.fits(A.rows(), A.cols()), "the basis does not belong to A's shape");
  return f;
}

// The cost as the Python side hands it over: (w, empty, empty) for a diagonal cost or
// (empty, W, R) for a full one, n = center's length; anything else is refused (a
// mismatch would read past an array).
inline dqk::Cost cost_of(const Vec& w_diag, const In& w_full, const In& root_full,
                         const Vec& center) {
  const Index n = center.size();
  const bool diagonal = w_diag.size() == n && w_full.size() == 0 && root_full.size() == 0;
  const bool full = w_diag.size() == 0 && w_full.rows() == n && w_full.cols() == n &&
                    root_full.rows() == n && root_full.cols() == n;
  require(diagonal || full,
          "the cost is (w (n), empty, empty) or (empty, W (n, n), R (n, n)) for n variables");
  return dqk::Cost(w_diag, w_full, root_full, center);
}

// The bindings of the step's parts and the step in one call (bind_step.cpp), of the exact
// solver, the factorisations and the certificate (bind_solver.cpp), and of the collision
// scene (bind_collision.cpp).
void bind_step(nb::module_& m);
void bind_solver(nb::module_& m);
void bind_collision(nb::module_& m);

}  // namespace dqk_binding
