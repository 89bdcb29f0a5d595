// Scoped HDF5 handles: every id we get from HDF5 (file, group, dataset, attribute, property
// list, dataspace, datatype) is owned by one H, which closes it when it goes out of scope, on the
// error paths too (an exception thrown while objects of a file are open closes them first, the
// file last: locals are destroyed in reverse order). Nothing is left open for HDF5's own exit
// handlers, which crash on a file left half-closed after a failed write (a full disk).
//
//   H file(H5Fcreate(...), H5Fclose);      // negative ids are held but never closed
//   H g(H5Gcreate2(file, ...), H5Gclose);
//   check_id(g, "create group /runs");     // h5io.hpp: throws xb::Error on a negative id
#pragma once

#include <hdf5.h>

#include <mutex>
#include <utility>

namespace xb::h5 {

// The libhdf5 linked here is not built thread-safe, and the Python package runs commands in
// threads (the GIL is released around them): every public function of harness/io that touches
// HDF5 holds this one process-wide lock (a Guard before its first H, so every handle is closed
// under it too). Recursive: a guarded function may call another. Taken after a results file's
// FileLock, never before (file_lock.hpp), so that a thread waiting for a file holds no Guard.
inline std::recursive_mutex& library_mutex() {
  static std::recursive_mutex m;
  return m;
}
class Guard {
 public:
  Guard() : lock_(library_mutex()) {}

 private:
  std::lock_guard<std::recursive_mutex> lock_;
};

class H {
 public:
  H(hid_t id, herr_t (*close)(hid_t)) : id(id), close_(close) {}
  ~H() { reset(); }
  H(H&& o) noexcept : id(std::exchange(o.id, H5I_INVALID_HID)), close_(o.close_) {}
  H& operator=(H&& o) noexcept {
    if (this != &o) {
      reset();
      id = std::exchange(o.id, H5I_INVALID_HID);
      close_ = o.close_;
    }
    return *this;
  }
  H(const H&) = delete;
  H& operator=(const H&) = delete;
  operator hid_t() const { return id; }
  // Closes now (a close that fails still gives up the id: HDF5 keeps no second chance).
  void reset() {
    if (id >= 0) close_(id);
    id = H5I_INVALID_HID;
  }

  hid_t id;

 private:
  herr_t (*close_)(hid_t);
};

}  // namespace xb::h5
