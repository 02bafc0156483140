"""ament_python package smarticle_common: the common contract of the smarticle stack."""

from setuptools import find_packages, setup

package_name = 'smarticle_common'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'test.*']),
    package_data={package_name: ['py.typed']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='Smarticle stack maintainers',
    maintainer_email='smarticles@example.org',
    description='The common contract of the smarticle stack: robot facts, topic contract, gait core, '
                'pair coordinates, pose conversions, parameter tables and the node helper.',
    license='Apache-2.0',
    python_requires='>=3.10',
)
