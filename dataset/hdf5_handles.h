// RAII owners for libhdf5's C handles. Every HDF5 object is an hid_t closed by its own function
// (H5Fclose, H5Gclose, ...), so each kind gets its own type: a file handle can never be closed
// with H5Dclose. Move-only, like render/mjr_handles.h and encode/av_handles.h.
#pragma once

#include <hdf5.h>

#include <optional>
#include <string>
#include <utility>

namespace fetchscope {

/// Owns one hid_t and closes it with `CloseFunction` (one instantiation per handle kind, below).
template <herr_t (*CloseFunction)(hid_t)>
class Hdf5Handle {
 public:
  Hdf5Handle() = default;
  /// Takes ownership of `id` (a negative id, HDF5's failure value, owns nothing).
  explicit Hdf5Handle(hid_t id) : id_(id) {}
  ~Hdf5Handle() { Reset(); }
  Hdf5Handle(const Hdf5Handle&) = delete;
  Hdf5Handle& operator=(const Hdf5Handle&) = delete;
  Hdf5Handle(Hdf5Handle&& other) noexcept : id_(std::exchange(other.id_, -1)) {}
  Hdf5Handle& operator=(Hdf5Handle&& other) noexcept {
    if (this != &other) {
      Reset();
      id_ = std::exchange(other.id_, -1);
    }
    return *this;
  }

  hid_t get() const { return id_; }                   ///< the id, for the C API
  bool valid() const { return id_ >= 0; }             ///< the call that made it succeeded
  explicit operator bool() const { return valid(); }  ///< same as valid()

  /// Closes now and reports whether the close succeeded (a file's close flushes: a full disk
  /// shows here).
  bool Close() {
    const herr_t status = id_ >= 0 ? CloseFunction(id_) : 0;
    id_ = -1;
    return status >= 0;
  }

 private:
  void Reset() noexcept {
    if (id_ >= 0) CloseFunction(id_);
    id_ = -1;
  }

  hid_t id_ = -1;
};

using H5File = Hdf5Handle<H5Fclose>;       ///< a file (H5Fcreate / H5Fopen)
using H5Group = Hdf5Handle<H5Gclose>;      ///< a group (H5Gcreate2 / H5Gopen2)
using H5Dataset = Hdf5Handle<H5Dclose>;    ///< a dataset (H5Dcreate2 / H5Dopen2)
using H5Dataspace = Hdf5Handle<H5Sclose>;  ///< a dataspace (H5Screate*, H5Dget_space)
using H5Datatype = Hdf5Handle<H5Tclose>;   ///< a datatype we made or got (not the predefined ones)
using H5Attribute = Hdf5Handle<H5Aclose>;  ///< an attribute (H5Acreate2 / H5Aopen)
using H5PropList = Hdf5Handle<H5Pclose>;   ///< a property list (H5Pcreate / H5Pcopy)

/// Reads the variable-length string attribute `name` of `object`; nullopt with `*why` ("has no
/// attribute NAME", "attribute NAME is not a string", "cannot read attribute NAME") otherwise.
inline std::optional<std::string> ReadStringAttribute(hid_t object, const char* name,
                                                      std::string* why) {
  const H5Attribute a(H5Aexists(object, name) > 0 ? H5Aopen(object, name, H5P_DEFAULT) : -1);
  if (!a) {
    *why = std::string("has no attribute ") + name;
    return std::nullopt;
  }
  const H5Datatype type(H5Aget_type(a.get()));
  if (H5Tget_class(type.get()) != H5T_STRING || H5Tis_variable_str(type.get()) <= 0) {
    *why = std::string("attribute ") + name + " is not a string";
    return std::nullopt;
  }
  char* text = nullptr;
  if (H5Aread(a.get(), type.get(), &text) < 0 || !text) {
    *why = std::string("cannot read attribute ") + name;
    return std::nullopt;
  }
  std::string out(text);
  H5free_memory(text);
  return out;
}

/// Writes `value` as a variable-length UTF-8 string attribute `name` of `object`, as h5py writes
/// a Python str. False where HDF5 refuses (the caller names the file).
inline bool WriteStringAttribute(hid_t object, const char* name, const std::string& value) {
  const H5Datatype type(H5Tcopy(H5T_C_S1));
  H5Tset_size(type.get(), H5T_VARIABLE);
  H5Tset_cset(type.get(), H5T_CSET_UTF8);
  const H5Dataspace space(H5Screate(H5S_SCALAR));
  const H5Attribute a(H5Acreate2(object, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT));
  const char* text = value.c_str();
  return a && H5Awrite(a.get(), type.get(), &text) >= 0;
}

}  // namespace fetchscope
