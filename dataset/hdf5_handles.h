// RAII owners for libhdf5's C handles. Every HDF5 object is an hid_t closed by its own function
// (H5Fclose, H5Gclose, ...), so each kind gets its own type: a file handle can never be closed
// with H5Dclose. Move-only, like render/mjr_handles.h and encode/av_handles.h.
#pragma once

#include <hdf5.h>

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

}  // namespace fetchscope
