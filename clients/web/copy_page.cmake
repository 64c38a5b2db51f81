# Puts the page into OUTPUT: the files of SOURCE/src and uPlot's ES module,
# stylesheet and licence from SOURCE/node_modules under vendor/.
# Usage: cmake -DSOURCE=clients/web -DOUTPUT=build/web -P copy_page.cmake
set(uplot ${SOURCE}/node_modules/uplot)
foreach(file dist/uPlot.esm.js dist/uPlot.min.css LICENSE)
  if(NOT EXISTS ${uplot}/${file})
    message(FATAL_ERROR "${uplot}/${file} is missing: the page's npm packages are not installed "
                        "(scripts/install-deps.sh runs scripts/install-web-deps.sh, which runs npm ci)")
  endif()
endforeach()
file(REMOVE_RECURSE ${OUTPUT})
file(COPY ${SOURCE}/src/ DESTINATION ${OUTPUT})
file(COPY ${uplot}/dist/uPlot.esm.js ${uplot}/dist/uPlot.min.css ${uplot}/LICENSE DESTINATION ${OUTPUT}/vendor)
