// The paper's Figs. 1, 2, 4 and 5 (Satoh, Yokoya and Takemura): three checkered cylinders crossing
// at a Schwarzschild hole above a checkered floor with the galaxy behind (Fig. 1), the same scene
// with no hole (Fig. 2), and the first and last frames of the movie in which the hole grows from
// M = 0.1 to M = 1.2 (Figs. 4 and 5). One vtkGeodesicSource per scene file, its image port
// written as a PNG (asrt::tools::writePng: VTK's PNG writer into a new temporary file that is
// renamed into place, so that nothing planted at the name is written through).
//
// Usage: asrt_example_paper_figures OUTPUT_DIR [SIZE]   (SIZE x SIZE pixels; default: the
// scenes' 200 x 200)
#include "vtkGeodesicSource.h"

#include "DataFiles.h"

#include "vtkImageData.h"
#include "vtkNew.h"

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

int main(int argc, char* argv[])
{
  if (argc < 2)
  {
    std::fprintf(stderr, "usage: %s OUTPUT_DIR [SIZE]\n", argv[0]);
    return 2;
  }
  const std::string out = argv[1];
  const int size = argc > 2 ? std::atoi(argv[2]) : 0;

  for (const char* figure :
       { "fig1-cylinders", "fig2-no-hole", "fig4-mass-start", "fig5-mass-end" })
  {
    vtkNew<vtkGeodesicSource> source;
    source->SetSceneFileName((std::string(ASRT_DATA_DIR) + "/scenes/" + figure + ".json").c_str());
    if (size > 0)
      source->SetResolution(size, size);
    source->Update();
    if (source->GetImageOutput()->GetNumberOfPoints() == 0)
      return 1; // the source has said why on stderr

    const std::string file = out + "/" + figure + ".png";
    try
    {
      asrt::tools::writePng(source->GetImageOutput(), file); // the image port: RGB "Colors"
    }
    catch (const std::exception& e)
    {
      std::fprintf(stderr, "%s: %s\n", argv[0], e.what());
      return 1;
    }
    std::printf("%s\n", file.c_str());
  }
  return 0;
}
