// The preview page's template (src/preview/viewer.html, built in): the data goes where the
// text "/*NP_DATA*/" stands.
#pragma once

namespace nonplanar::preview {

/// The whole page, NUL-terminated.
const char* viewer_html();

}  // namespace nonplanar::preview
