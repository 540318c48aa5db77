// lib3mf's C functions, loaded the first time a 3MF is read or written (dlopen) rather than
// when the program starts: lib3mf and the zip and crypto libraries it needs cost every run
// about 5 ms of its start (15 ms -> 10 ms for an empty main() linked as nonplanar-core is),
// 3 % of slicing the sine roof, and most runs read an STL and write G-code.
#pragma once

#include <Model/COM/NMR_DLLInterfaces.h>

#include <string>

/// The lib3mf functions the program calls (NMR::lib3mf_<name>).
#define NONPLANAR_LIB3MF_FUNCTIONS(X)   \
  X(release)                            \
  X(getlasterror)                       \
  X(createmodel)                        \
  X(resource_getresourceid)             \
  X(object_ismeshobject)                \
  X(object_iscomponentsobject)          \
  X(object_getnameutf8)                 \
  X(object_setnameutf8)                 \
  X(meshobject_gettrianglecount)        \
  X(meshobject_getvertexcount)          \
  X(meshobject_getvertices)             \
  X(meshobject_gettriangleindices)      \
  X(meshobject_setgeometry)             \
  X(componentsobject_getcomponentcount) \
  X(componentsobject_getcomponent)      \
  X(component_getobjectresource)        \
  X(component_hastransform)             \
  X(component_gettransform)             \
  X(model_queryreader)                  \
  X(model_querywriter)                  \
  X(model_getbuilditems)                \
  X(model_getunit)                      \
  X(model_addmeshobject)                \
  X(model_addbuilditem)                 \
  X(model_addcustomcontenttypeutf8)     \
  X(model_addattachmentutf8)            \
  X(reader_readfrombuffer)              \
  X(writer_getstreamsize)               \
  X(writer_writetobuffer)               \
  X(builditemiterator_movenext)         \
  X(builditemiterator_getcurrent)       \
  X(builditem_getobjectresource)        \
  X(builditem_hasobjecttransform)       \
  X(builditem_getobjecttransform)       \
  X(attachment_readfrombuffer)

namespace nonplanar::io {

/// One pointer per function of NONPLANAR_LIB3MF_FUNCTIONS, named without the prefix.
struct Lib3mf {
#define NONPLANAR_LIB3MF_FIELD(name) decltype(&NMR::lib3mf_##name) name = nullptr;
  NONPLANAR_LIB3MF_FUNCTIONS(NONPLANAR_LIB3MF_FIELD)
#undef NONPLANAR_LIB3MF_FIELD
};

/// Loads lib3mf once (thread-safe) and returns its functions; null when the library or one
/// of them cannot be loaded, with `why` (if given) saying what and how to mend it.
const Lib3mf* load_lib3mf(std::string* why = nullptr);

/// The functions of a lib3mf load_lib3mf() has loaded (call that first).
const Lib3mf& lib3mf();

}  // namespace nonplanar::io
