#pragma once
// Objects that never ran __init__: `Cls.__new__(Cls)`, or a pickle that names a class and carries
// no state, make a Python object whose C++ value does not exist. pybind11 allocates that value,
// uninitialised, the first time a method takes the object; every bound class routes that one
// allocation to a TypeError instead, so such an object can be created and dropped but not used.

#include <cstddef>
#include <string>

#include <pybind11/pybind11.h>

namespace knnocc::python {

/// Makes every use of a `T` created without __init__ (or __setstate__) a TypeError naming `cls`.
/// Call once, right after binding the class.
template <class T>
void refuse_uninitialised(const pybind11::class_<T>& cls) {
  namespace py = pybind11;
  static std::string message;  // one per bound class; read when the refusal is raised
  message = "knnocc." + py::str(cls.attr("__name__")).cast<std::string>() +
            ": this object was made without __init__ (Cls.__new__, or a pickle without its "
            "state) and holds nothing; create it by calling the class";
  py::detail::type_info* info = py::detail::get_type_info(typeid(T), true);
  info->operator_new = [](std::size_t) -> void* { throw py::type_error(message); };
}

}  // namespace knnocc::python
